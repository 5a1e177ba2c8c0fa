//! Across hardware: the papers' GPUs' published peaks (`reports/papers/hardware.csv`, each
//! with its source) and ours as calibrated (`tetbench calibrate`, stored in every run's
//! machine record), so that an absolute rate the paper measured on its GPU can be judged on
//! another adapter relative to what each can do at most (docs/reproduction.md, "Across
//! hardware").

use anyhow::{bail, Context as _};

/// The file, compiled in like the claims.
pub const HARDWARE_CSV: &str = include_str!("../../../reports/papers/hardware.csv");
const FILE: &str = "reports/papers/hardware.csv";

/// One paper's GPU with its published peaks.
#[derive(Debug, Clone, PartialEq)]
pub struct PaperGpu {
    pub paper: String,
    pub gpu: String,
    /// Pixels written per second (ROPs × core clock).
    pub fill_pixels_per_sec: Option<f64>,
    pub vertices_per_sec: Option<f64>,
    pub source: String,
}

/// Our adapter's calibrated peaks (from the runs' machine record).
#[derive(Debug, Clone, PartialEq)]
pub struct OurPeaks {
    pub adapter: String,
    /// Where the figures come from: the control measured beside the judged rows, or the
    /// cached calibration and its date.
    pub source: String,
    /// Blended fragments per second into the renderers' `Rgba32Float` targets.
    pub fill_fragments_per_sec: f64,
    pub triangles_per_sec: f64,
}

/// Parses the hardware file; errors name the file, the line and what is wrong.
pub fn parse(text: &str, file: &str) -> anyhow::Result<Vec<PaperGpu>> {
    let mut reader = super::transcription::reader_with_header(
        text,
        file,
        &[
            "paper",
            "gpu",
            "fill_pixels_per_sec",
            "vertices_per_sec",
            "source",
        ],
    )?;
    let mut out = vec![];
    for (i, rec) in reader.records().enumerate() {
        let line = i + 2;
        let rec = rec.with_context(|| format!("{file}: line {line}"))?;
        let f = |j: usize| rec.get(j).unwrap_or("").trim().to_string();
        let num = |j: usize| -> anyhow::Result<Option<f64>> {
            let s = f(j);
            if s.is_empty() {
                return Ok(None);
            }
            match s.parse::<f64>() {
                Ok(v) if v > 0.0 => Ok(Some(v)),
                _ => bail!("{file}: line {line}: {:?} is not a positive number", s),
            }
        };
        if f(4).is_empty() {
            bail!("{file}: line {line}: a peak needs its source");
        }
        out.push(PaperGpu {
            paper: f(0),
            gpu: f(1),
            fill_pixels_per_sec: num(2)?,
            vertices_per_sec: num(3)?,
            source: f(4),
        });
    }
    Ok(out)
}

/// The GPU of `paper`, if transcribed.
pub fn paper_gpu(paper: &str) -> Option<PaperGpu> {
    parse(HARDWARE_CSV, FILE)
        .expect("reports/papers/hardware.csv parses (tested)")
        .into_iter()
        .find(|g| g.paper == paper)
}

/// Our peaks from a run's machine record (the cached calibration).
pub fn our_peaks(c: &crate::results::machine::Calibration) -> OurPeaks {
    OurPeaks {
        adapter: c.adapter.clone(),
        source: format!("the cached calibration of {}", c.date_utc),
        fill_fragments_per_sec: c.fill_fragments_per_sec,
        triangles_per_sec: c.triangles_per_sec,
    }
}

/// Our figures at the moment of the judged rows: the per-figure median over every round's
/// control the rows carry (`None` where no row has one, or the control measured no fill).
pub fn control_peaks(adapter: &str, rows: &[crate::results::Row]) -> Option<OurPeaks> {
    use crate::results::machine::Figure;
    let rounds: Vec<&crate::results::control::Figures> =
        rows.iter().flat_map(|r| r.round_control.iter()).collect();
    let median = crate::results::control::median_figures(rounds.iter().copied());
    Some(OurPeaks {
        adapter: adapter.to_string(),
        source: format!(
            "the control measured beside the judged rows ({} rounds)",
            rounds.len()
        ),
        fill_fragments_per_sec: *median.get(&Figure::FillFragmentsPerSec)?,
        triangles_per_sec: median.get(&Figure::TrianglesPerSec).copied().unwrap_or(0.0),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_papers_gpus_parse_with_sources_and_bad_lines_are_refused() {
        let all = parse(HARDWARE_CSV, FILE).unwrap();
        assert!(all.iter().all(|g| !g.source.is_empty()));
        assert_eq!(paper_gpu("havs").unwrap().fill_pixels_per_sec, Some(3.04e9));
        let bad = "paper,gpu,fill_pixels_per_sec,vertices_per_sec,source\nhavs,x,-1,,s\n";
        assert!(parse(bad, "h.csv")
            .unwrap_err()
            .to_string()
            .contains("h.csv: line 2"));
        let nosource = "paper,gpu,fill_pixels_per_sec,vertices_per_sec,source\nhavs,x,1,,\n";
        assert!(parse(nosource, "h.csv")
            .unwrap_err()
            .to_string()
            .contains("source"));
    }
}
