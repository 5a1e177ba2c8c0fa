//! The papers' claims as data (`reports/papers/claims.csv`) and their evaluation with the one
//! verdict rule of [`super::verdict`].
//!
//! Each claim names the section or table it rests on, says in our words what the paper
//! claims, and says what it compares: a metric, the data sets (one verdict per data set), the
//! variants of each side spelled out (`algorithm:key=value;…`, optionally `@dataset` to pin a
//! side to one data set), what it expects (`a<b`, `a>b`, `a>N`, `a<N`, `a in LO..HI`,
//! `a/b in LO..HI`, `a=N`, or `a=TABLE.COLUMN`: the paper's own cell for the data set), its
//! relative tolerance and what it depends on (`none`, `cpu`, `gpu`). `source` is `paper` for
//! what the paper states and `ours` for a reading of its numbers that its text does not make.
//!
//! Metrics read from a run's rows: `total_ms`, `gpu_ms`, `cpu_ms`, `fps`, `tets_per_sec`,
//! `gpu_tets_per_sec`, `bytes_per_tet`, `psnr_db`, `counter:NAME`, `stage:NAME`,
//! `stage_share:NAME` (the stage over the most expensive other stage) and `view_range:METRIC`
//! (range over the viewpoints divided by their mean). Other metrics (the CPU analyses: sorts,
//! the k-buffer, the classifier, data set sizes) come from the paper's own measurements.

use anyhow::{bail, Context as _};
use render_core::Settings;

use super::verdict::{self, Check, Evaluation, Expect, Hardware, Sample, Side};
use crate::results::Row;

/// The claims file, compiled in like the tables.
pub const CLAIMS_CSV: &str = include_str!("../../../reports/papers/claims.csv");
const FILE: &str = "reports/papers/claims.csv";

/// Whether the paper states the claim or we read it off its numbers.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Source {
    Paper,
    Ours,
}

/// One side of a claim: an algorithm (or one of the papers' CPU analyses) and the settings
/// that pick its variant.
#[derive(Debug, Clone, PartialEq)]
pub struct VariantSpec {
    pub algorithm: String,
    pub settings: Settings,
    /// Pins the side to one data set whatever the claim's data sets are.
    pub dataset: Option<String>,
}

impl VariantSpec {
    pub fn parse(text: &str) -> Result<VariantSpec, String> {
        let (body, dataset) = match text.split_once('@') {
            Some((b, d)) => (b, Some(d.trim().to_string())),
            None => (text, None),
        };
        let (algorithm, settings) = match body.split_once(':') {
            Some((a, s)) => (a.trim(), s),
            None => (body.trim(), ""),
        };
        if algorithm.is_empty() {
            return Err(format!("{text:?}: no algorithm"));
        }
        // The papers' CPU analyses (`sort-analysis`) are not algorithms: their settings are
        // typed by inference.
        let settings = crate::algorithms::parse_settings(algorithm, settings)
            .map_err(|e| format!("{text:?}: {e}"))?;
        Ok(VariantSpec {
            algorithm: algorithm.to_string(),
            settings,
            dataset,
        })
    }

    pub fn settings_text(&self) -> String {
        self.settings.to_string()
    }

    /// `algorithm settings on dataset`: what a verdict names.
    pub fn label(&self, dataset: Option<&str>) -> String {
        let mut s = self.algorithm.clone();
        if !self.settings.is_empty() {
            s.push(' ');
            s.push_str(&self.settings_text());
        }
        if let Some(d) = dataset {
            s.push_str(" on ");
            s.push_str(d);
        }
        s
    }

    /// The value this side asks for a setting, if it pins it.
    pub fn setting(&self, key: &str) -> Option<String> {
        self.settings.text(key)
    }

    fn matches(&self, row: &Row) -> bool {
        row.algorithm == self.algorithm
            && self
                .settings
                .iter()
                .all(|(k, v)| row.settings.get(k) == Some(v))
    }
}

/// What a claim expects, before the paper's cells are looked up.
#[derive(Debug, Clone, PartialEq)]
pub enum ExpectSpec {
    Fixed(Expect),
    /// `a=TABLE.COLUMN`: equal to the paper's cell of the data set's row.
    PaperCell {
        table: String,
        column: String,
    },
}

impl ExpectSpec {
    pub fn parse(text: &str) -> Result<ExpectSpec, String> {
        let t = text.replace(' ', "");
        let num = |s: &str| {
            s.parse::<f64>()
                .map_err(|_| format!("expect {text:?}: {s:?} is not a number"))
        };
        let band = |s: &str| -> Result<(f64, f64), String> {
            let (lo, hi) = s
                .split_once("..")
                .ok_or_else(|| format!("expect {text:?}: a band is LO..HI"))?;
            Ok((num(lo)?, num(hi)?))
        };
        Ok(ExpectSpec::Fixed(match t.as_str() {
            "a<b" => Expect::Less,
            "a>b" => Expect::Greater,
            _ if t.starts_with("a/bin") => {
                let (lo, hi) = band(&t[5..])?;
                Expect::Band(lo, hi)
            }
            _ if t.starts_with("ain") => {
                let (lo, hi) = band(&t[3..])?;
                Expect::Band(lo, hi)
            }
            _ if t.starts_with("a>") => Expect::Above(num(&t[2..])?),
            _ if t.starts_with("a<") => Expect::Below(num(&t[2..])?),
            _ if t.starts_with("a=") => {
                let v = &t[2..];
                if let Ok(x) = v.parse::<f64>() {
                    Expect::Equals(x)
                } else {
                    let (table, column) = v
                        .split_once('.')
                        .ok_or_else(|| format!("expect {text:?}: a=N or a=TABLE.COLUMN"))?;
                    return Ok(ExpectSpec::PaperCell {
                        table: table.to_string(),
                        column: column.to_string(),
                    });
                }
            }
            _ => return Err(format!("expect {text:?} is not one of a<b, a>b, a>N, a<N, a in LO..HI, a/b in LO..HI, a=N, a=TABLE.COLUMN")),
        }))
    }

    /// Whether the claim compares two sides.
    pub fn needs_b(&self) -> bool {
        matches!(self, ExpectSpec::Fixed(Expect::Less | Expect::Greater))
    }
}

/// One claim of a paper.
#[derive(Debug, Clone, PartialEq)]
pub struct Claim {
    pub paper: String,
    pub id: String,
    pub source: Source,
    pub cites: String,
    pub text: String,
    pub metric: String,
    /// One verdict per data set; empty: one verdict (sides pinned with `@` or no data set).
    pub datasets: Vec<String>,
    pub a: VariantSpec,
    pub b: Option<VariantSpec>,
    pub expect: ExpectSpec,
    pub tolerance: f64,
    pub hardware: Hardware,
    /// The expectation as written in the file.
    pub expect_text: String,
}

/// Parses a claims file; errors name the file, the line and what is wrong.
pub fn parse(text: &str, file: &str) -> anyhow::Result<Vec<Claim>> {
    let mut reader = csv::ReaderBuilder::new()
        .has_headers(true)
        .from_reader(text.as_bytes());
    let header: Vec<String> = reader
        .headers()
        .with_context(|| format!("{file}: header"))?
        .iter()
        .map(str::to_string)
        .collect();
    let expected = [
        "paper",
        "id",
        "source",
        "cites",
        "claim",
        "metric",
        "datasets",
        "a",
        "b",
        "expect",
        "tolerance",
        "hardware",
    ];
    if header != expected {
        bail!(
            "{file}: header is {header:?}, expected {}",
            expected.join(",")
        );
    }
    let mut claims: Vec<Claim> = vec![];
    for (i, rec) in reader.records().enumerate() {
        let line = i + 2;
        let rec = rec.with_context(|| format!("{file}: line {line}"))?;
        let f = |j: usize| rec.get(j).unwrap_or("").trim().to_string();
        let err = |what: String| anyhow::anyhow!("{file}: line {line}: {what}");
        let source = match f(2).as_str() {
            "paper" => Source::Paper,
            "ours" => Source::Ours,
            s => return Err(err(format!("source {s:?} is not paper or ours"))),
        };
        let hardware = match f(11).as_str() {
            "none" => Hardware::None,
            "cpu" => Hardware::Cpu,
            "gpu" => Hardware::Gpu,
            s => return Err(err(format!("hardware {s:?} is not none, cpu or gpu"))),
        };
        let tolerance: f64 = f(10)
            .parse()
            .map_err(|_| err(format!("tolerance {:?} is not a number", f(10))))?;
        if !(0.0..1.0).contains(&tolerance) {
            return Err(err(format!("tolerance {tolerance} is not in [0, 1)")));
        }
        let a = VariantSpec::parse(&f(7)).map_err(err)?;
        let b = match f(8) {
            s if s.is_empty() => None,
            s => Some(VariantSpec::parse(&s).map_err(err)?),
        };
        let expect = ExpectSpec::parse(&f(9)).map_err(err)?;
        let needs_b = expect.needs_b() || f(9).replace(' ', "").starts_with("a/b");
        if needs_b != b.is_some() {
            return Err(err(format!(
                "expect {:?} {} a second side (column b)",
                f(9),
                if needs_b { "needs" } else { "takes no" }
            )));
        }
        for (name, value) in [
            ("paper", f(0)),
            ("id", f(1)),
            ("cites", f(3)),
            ("claim", f(4)),
            ("metric", f(5)),
        ] {
            if value.is_empty() {
                return Err(err(format!("{name} is empty")));
            }
        }
        let claim = Claim {
            paper: f(0),
            id: f(1),
            source,
            cites: f(3),
            text: f(4),
            metric: f(5),
            datasets: f(6)
                .split(';')
                .map(str::trim)
                .filter(|s| !s.is_empty())
                .map(String::from)
                .collect(),
            a,
            b,
            expect,
            tolerance,
            hardware,
            expect_text: f(9),
        };
        if claims
            .iter()
            .any(|c| c.paper == claim.paper && c.id == claim.id)
        {
            return Err(err(format!("{} {} appears twice", claim.paper, claim.id)));
        }
        claims.push(claim);
    }
    Ok(claims)
}

/// Every claim of the compiled-in file.
pub fn all() -> anyhow::Result<Vec<Claim>> {
    parse(CLAIMS_CSV, FILE)
}

/// The claims of one paper, in the file's order.
pub fn of(paper: &str) -> Vec<Claim> {
    all()
        .expect("reports/papers/claims.csv parses (tested)")
        .into_iter()
        .filter(|c| c.paper == paper)
        .collect()
}

/// A claim's verdict on one data set (or on none).
#[derive(Debug, Clone, PartialEq)]
pub struct ClaimResult {
    pub claim: Claim,
    pub dataset: Option<String>,
    pub evaluation: Evaluation,
}

/// Where the numbers come from: the run's rows, the paper's own analyses, and why an
/// algorithm has no rows.
/// A side from the paper's CPU analyses for (metric, variant, data set), or `None` when the
/// metric is not one of them.
pub type AnalysisSide<'a> =
    dyn Fn(&str, &VariantSpec, Option<&str>) -> Option<Result<Side, String>> + 'a;

pub struct Inputs<'a> {
    pub rows: &'a [Row],
    /// A side from the paper's CPU analyses (`None`: the metric is not one of them).
    pub analysis: &'a AnalysisSide<'a>,
    /// Why `algorithm` has no value on a data set.
    pub why_missing: &'a dyn Fn(&str, &str) -> String,
    /// Whether the GPU numbers came from a software rasteriser.
    pub software_adapter: bool,
}

/// Whether rows were measured on a software rasteriser (lavapipe, WARP, SwiftShader report a
/// CPU device type).
pub fn software_adapter(rows: &[Row]) -> bool {
    rows.iter()
        .any(|r| r.device_type.eq_ignore_ascii_case("cpu"))
}

/// Evaluates every claim of `paper`.
pub fn evaluate_all(paper: &str, inputs: &Inputs) -> Vec<ClaimResult> {
    of(paper)
        .into_iter()
        .flat_map(|c| evaluate(&c, inputs))
        .collect()
}

/// One verdict per data set of the claim.
pub fn evaluate(claim: &Claim, inputs: &Inputs) -> Vec<ClaimResult> {
    let datasets: Vec<Option<String>> = if claim.datasets.is_empty() {
        vec![None]
    } else {
        claim.datasets.iter().cloned().map(Some).collect()
    };
    datasets
        .into_iter()
        .map(|d| {
            let evaluation = evaluate_one(claim, d.as_deref(), inputs);
            ClaimResult {
                claim: claim.clone(),
                dataset: d,
                evaluation,
            }
        })
        .collect()
}

fn evaluate_one(claim: &Claim, dataset: Option<&str>, inputs: &Inputs) -> Evaluation {
    let expect = match &claim.expect {
        ExpectSpec::Fixed(e) => *e,
        ExpectSpec::PaperCell { table, column } => {
            let Some(d) = dataset else {
                return Evaluation::not_checkable(format!(
                    "{} {}: a=TABLE.COLUMN needs a data set",
                    claim.paper, claim.id
                ));
            };
            let row = super::transcription::paper_name(&claim.paper, d).unwrap_or(d);
            match super::transcription::table(table)
                .ok()
                .and_then(|t| t.value(row, column))
            {
                Some(v) => Expect::Equals(v),
                None => {
                    return Evaluation::not_checkable(format!(
                        "the paper gives no {table} {column} for {row}"
                    ))
                }
            }
        }
    };
    let check = Check {
        expect,
        tolerance: claim.tolerance,
        hardware: claim.hardware,
    };
    let a = side(claim, &claim.a, dataset, inputs);
    let b = claim.b.as_ref().map(|b| side(claim, b, dataset, inputs));
    verdict::evaluate(
        &check,
        a.as_ref().map_err(Clone::clone),
        b.as_ref().map(|r| r.as_ref().map_err(Clone::clone)),
        inputs.software_adapter,
    )
}

/// The samples of one side on one data set.
fn side(
    claim: &Claim,
    spec: &VariantSpec,
    dataset: Option<&str>,
    inputs: &Inputs,
) -> Result<Side, String> {
    let d = spec.dataset.as_deref().or(dataset);
    if let Some(s) = (inputs.analysis)(&claim.metric, spec, d) {
        return s;
    }
    let Some(d) = d else {
        return Err(format!(
            "{}: metric {} needs a data set",
            spec.label(None),
            claim.metric
        ));
    };
    side_from_rows(&claim.metric, spec, d, inputs)
}

/// A side from a run's rows: exactly one variant must match the spec (a claim that does not
/// pin its variant is refused, never decided by whichever variant came first).
pub fn side_from_rows(
    metric: &str,
    spec: &VariantSpec,
    dataset: &str,
    inputs: &Inputs,
) -> Result<Side, String> {
    let label = spec.label(Some(dataset));
    let rows: Vec<&Row> = inputs
        .rows
        .iter()
        .filter(|r| r.dataset == dataset && r.ok() && spec.matches(r))
        .collect();
    let mut variants: Vec<&Settings> = rows.iter().map(|r| &r.settings).collect();
    variants.sort();
    variants.dedup();
    if variants.len() > 1 {
        return Err(format!(
            "{label}: {} variants match ({}); the claim must name one",
            variants.len(),
            variants
                .iter()
                .map(|v| v.to_string())
                .collect::<Vec<_>>()
                .join(" | ")
        ));
    }
    if rows.is_empty() {
        return Err(format!(
            "{label}: {}",
            (inputs.why_missing)(&spec.algorithm, dataset)
        ));
    }
    let label = format!("{} {} on {dataset}", spec.algorithm, variants[0]);
    if let Some(inner) = metric.strip_prefix("view_range:") {
        let values: Vec<f64> = rows
            .iter()
            .filter_map(|r| row_sample(inner, r).ok().map(|s| s.value))
            .collect();
        if values.len() < 2 {
            return Err(format!(
                "{label}: {metric} needs at least two viewpoints, has {}",
                values.len()
            ));
        }
        let mean = values.iter().sum::<f64>() / values.len() as f64;
        let (lo, hi) = values
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &v| {
                (l.min(v), h.max(v))
            });
        return Ok(Side::new(
            format!(
                "{label}, {inner} range/mean over {} viewpoints",
                values.len()
            ),
            vec![Sample::exact("views", (hi - lo) / mean)],
        ));
    }
    let mut samples = vec![];
    let mut first_err = None;
    for r in rows {
        match row_sample(metric, r) {
            Ok(s) => samples.push(s),
            Err(e) => {
                first_err.get_or_insert(e);
            }
        }
    }
    if samples.is_empty() {
        return Err(format!(
            "{label}: {}",
            first_err.unwrap_or_else(|| format!("no {metric}"))
        ));
    }
    Ok(Side::new(format!("{label}, {metric}"), samples))
}

/// One row's value of a metric, with its frames' range where the row has one.
pub fn row_sample(metric: &str, r: &Row) -> Result<Sample, String> {
    let key = r.viewpoint.clone();
    let timed = |v: Option<f64>, lo: Option<f64>, hi: Option<f64>| -> Result<Sample, String> {
        let v = v.ok_or_else(|| format!("no {metric} in its rows"))?;
        Ok(Sample {
            key: key.clone(),
            value: v,
            min: lo.unwrap_or(v),
            max: hi.unwrap_or(v),
            frames: r.frames.max(1),
        })
    };
    // A rate from a time: the slowest frame gives the lowest rate.
    let rate = |num: f64, s: Sample| Sample {
        value: num / s.value,
        min: num / s.max,
        max: num / s.min,
        ..s
    };
    let exact = |v: Option<f64>| {
        v.map(|v| Sample::exact(key.clone(), v))
            .ok_or_else(|| format!("no {metric} in its rows"))
    };
    match metric {
        "total_ms" => timed(r.total_ms, r.total_ms_min, r.total_ms_max),
        "gpu_ms" => timed(r.gpu_ms, r.gpu_ms_min, r.gpu_ms_max),
        "cpu_ms" => timed(r.cpu_ms, r.cpu_ms_min, r.cpu_ms_max),
        "fps" => Ok(rate(
            1e3,
            timed(r.total_ms, r.total_ms_min, r.total_ms_max)?,
        )),
        "tets_per_sec" => Ok(rate(
            r.tets as f64 * 1e3,
            timed(r.total_ms, r.total_ms_min, r.total_ms_max)?,
        )),
        "gpu_tets_per_sec" => Ok(rate(
            r.tets as f64 * 1e3,
            timed(r.gpu_ms, r.gpu_ms_min, r.gpu_ms_max)?,
        )),
        "bytes_per_tet" => exact(r.bytes_per_tet),
        "psnr_db" => exact(r.psnr_db),
        _ => {
            if let Some(name) = metric.strip_prefix("counter:") {
                return exact(r.counter(name));
            }
            if let Some(name) = metric.strip_prefix("stage:") {
                return timed(r.stage_ms(name), None, None).map_err(|_| no_stage(name, r));
            }
            if let Some(name) = metric.strip_prefix("stage_share:") {
                let this = r.stage_ms(name).ok_or_else(|| no_stage(name, r))?;
                let other = r
                    .stages
                    .iter()
                    .filter(|(k, _)| *k != name)
                    .map(|(_, v)| v)
                    .fold(0.0f64, f64::max);
                if other <= 0.0 {
                    return Err(format!("no stage besides {name} in its rows"));
                }
                return timed(Some(this / other), None, None);
            }
            Err(format!("unknown metric {metric:?}"))
        }
    }
}

fn no_stage(name: &str, r: &Row) -> String {
    let have: Vec<&str> = r.stages.names().collect();
    format!(
        "no stage named {name} in its rows (stages timed: {})",
        if have.is_empty() {
            "none".to_string()
        } else {
            have.join(", ")
        }
    )
}

/// Counts of each verdict, in [`verdict::Verdict::ALL`]'s order.
pub fn tally(results: &[ClaimResult]) -> Vec<(verdict::Verdict, usize)> {
    verdict::Verdict::ALL
        .iter()
        .map(|v| {
            (
                *v,
                results
                    .iter()
                    .filter(|r| r.evaluation.verdict == *v)
                    .count(),
            )
        })
        .collect()
}

/// The verdicts as a Markdown table: claim, where, verdict, the numbers and variants used.
pub fn markdown(results: &[ClaimResult]) -> String {
    use std::fmt::Write as _;
    let mut md = String::from(
        "| claim | cites | data set | verdict | numbers (variants named) |\n|---|---|---|---|---|\n",
    );
    for r in results {
        let c = &r.claim;
        let label = match c.source {
            Source::Paper => format!("**{}** {}", c.id, c.text),
            Source::Ours => format!("**{}** (ours, not the paper's) {}", c.id, c.text),
        };
        let _ = writeln!(
            md,
            "| {} | {} | {} | {} | {} |",
            cell(&label),
            cell(&c.cites),
            r.dataset.as_deref().unwrap_or("–"),
            r.evaluation.verdict.label(),
            cell(&r.evaluation.numbers)
        );
    }
    md
}

fn cell(s: &str) -> String {
    s.replace('|', "\\|").replace('\n', " ")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn variant_specs_and_expectations_parse() {
        let v = VariantSpec::parse("havs:k=2;sort=cpu-radix@spx2").unwrap();
        assert_eq!(v.algorithm, "havs");
        assert_eq!(v.settings.int("k"), Some(2));
        assert_eq!(v.dataset.as_deref(), Some("spx2"));
        assert_eq!(v.label(Some("spx2")), "havs k=2;sort=cpu-radix on spx2");
        assert!(VariantSpec::parse("havs:k2").is_err());
        assert_eq!(
            ExpectSpec::parse("a/b in 2..2.5").unwrap(),
            ExpectSpec::Fixed(Expect::Band(2.0, 2.5))
        );
        assert_eq!(
            ExpectSpec::parse("a>15000000").unwrap(),
            ExpectSpec::Fixed(Expect::Above(15e6))
        );
        assert_eq!(
            ExpectSpec::parse("a=havs_table2.fragments_count").unwrap(),
            ExpectSpec::PaperCell {
                table: "havs_table2".into(),
                column: "fragments_count".into()
            }
        );
        assert!(ExpectSpec::parse("a≈b").is_err());
    }

    #[test]
    fn a_bad_claims_file_is_refused_with_file_and_line() {
        let head = "paper,id,source,cites,claim,metric,datasets,a,b,expect,tolerance,hardware\n";
        let bad = format!("{head}havs,H1,paper,§5.1,x,total_ms,spx2,havs:k=2,,a<b,0,gpu\n");
        let e = parse(&bad, "claims.csv").unwrap_err().to_string();
        assert!(
            e.contains("claims.csv: line 2") && e.contains("second side"),
            "{e}"
        );
        let bad = format!("{head}havs,H1,maybe,§5.1,x,total_ms,spx2,havs,,a>1,0,gpu\n");
        assert!(parse(&bad, "c").unwrap_err().to_string().contains("source"));
        let twice = format!(
            "{head}havs,H1,paper,§5.1,x,total_ms,,havs,,a>1,0,gpu\nhavs,H1,paper,§5.1,x,total_ms,,havs,,a>1,0,gpu\n"
        );
        assert!(parse(&twice, "c")
            .unwrap_err()
            .to_string()
            .contains("twice"));
    }

    fn row(settings: &str, viewpoint: &str, total: f64, frames: u32) -> Row {
        Row {
            algorithm: "raycast".into(),
            settings: Settings::parse(settings).unwrap(),
            dataset: "spx1".into(),
            tets: 1000,
            viewpoint: viewpoint.into(),
            total_ms: Some(total),
            total_ms_min: Some(total - 1.0),
            total_ms_max: Some(total + 1.0),
            frames,
            device_type: "DiscreteGpu".into(),
            ..Default::default()
        }
    }

    fn inputs(rows: &[Row]) -> Inputs<'_> {
        Inputs {
            rows,
            analysis: &|_, _, _| None,
            why_missing: &|a, d| format!("{a} not measured on {d}"),
            software_adapter: software_adapter(rows),
        }
    }

    #[test]
    fn a_claim_that_does_not_pin_its_variant_is_not_decided_by_the_first_one_found() {
        let rows = vec![
            row("tiles=5x5;table=2d;mode=passes", "+x", 100.0, 5),
            row("tiles=5x5;table=2d;mode=loop", "+x", 300.0, 5),
            row("tiles=1x1;table=2d;mode=passes", "+x", 200.0, 5),
        ];
        let loose = VariantSpec::parse("raycast:tiles=5x5").unwrap();
        let e = side_from_rows("total_ms", &loose, "spx1", &inputs(&rows)).unwrap_err();
        assert!(e.contains("2 variants match"), "{e}");
        let pinned = VariantSpec::parse("raycast:tiles=5x5;mode=passes").unwrap();
        let s = side_from_rows("total_ms", &pinned, "spx1", &inputs(&rows)).unwrap();
        assert!(s.label.contains("mode=passes"), "{}", s.label);
        assert_eq!(s.centre(), 100.0);
        // Pinned to the loop variant the ordering flips.
        let claim = |a: &str| Claim {
            paper: "raycast".into(),
            id: "X".into(),
            source: Source::Ours,
            cites: "§4".into(),
            text: "t".into(),
            metric: "total_ms".into(),
            datasets: vec!["spx1".into()],
            a: VariantSpec::parse(a).unwrap(),
            b: Some(VariantSpec::parse("raycast:tiles=1x1").unwrap()),
            expect: ExpectSpec::Fixed(Expect::Less),
            tolerance: 0.0,
            hardware: Hardware::Gpu,
            expect_text: "a<b".into(),
        };
        let v = |a: &str| evaluate(&claim(a), &inputs(&rows))[0].evaluation.verdict;
        assert_eq!(v("raycast:tiles=5x5;mode=passes"), verdict::Verdict::Holds);
        assert_eq!(
            v("raycast:tiles=5x5;mode=loop"),
            verdict::Verdict::DoesNotHold
        );
        assert_eq!(v("raycast:tiles=5x5"), verdict::Verdict::NotCheckable);
    }

    #[test]
    fn rates_invert_the_frame_range_and_stage_shares_name_missing_stages() {
        let mut r = row("tiles=1x1", "+x", 100.0, 3);
        let fps = row_sample("fps", &r).unwrap();
        assert_eq!(fps.value, 10.0);
        assert!(fps.min < 10.0 && fps.max > 10.0);
        r.stages = "wait=9;buckets=3;splat=1".into();
        let e = row_sample("stage_share:sort", &r).unwrap_err();
        assert!(e.contains("wait, buckets, splat"), "{e}");
        assert_eq!(row_sample("stage_share:wait", &r).unwrap().value, 3.0);
        assert!(row_sample("no-such-metric", &r).is_err());
    }
}
