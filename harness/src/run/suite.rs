//! The embedded default suite (`tetbench run` with no arguments) and the parsing of
//! `--viewpoints`.

use render_core::{fixed_viewpoints, orbit_viewpoints, Viewpoint};

/// What `tetbench run` measures when no data set is named: generated meshes only (no files
/// needed), every algorithm, three viewpoints, a modest viewport. Sized to finish in under two
/// minutes on a 2-core machine without a GPU (Mesa lavapipe), reference images included; the
/// docs/measurements.md gives the measured time.
pub struct Suite {
    pub datasets: &'static [&'static str],
    pub viewpoints: &'static str,
    pub resolution: u32,
    pub frames: u32,
    pub warmup: u32,
    pub rounds: u32,
}

pub const DEFAULT_SUITE: Suite = Suite {
    // A convex box and a non-convex shell (rays leave and re-enter), both with smooth fields.
    datasets: &["box:10k", "shell:10k"],
    // An axis view and two cube diagonals of the 14 fixed viewpoints.
    viewpoints: "+x,+x+y+z,-x+y-z",
    resolution: 128,
    // Three rounds of one timed frame each: three samples per row taken seconds apart, so
    // that `tetbench compare` tests independent samples (see `run::DatasetContext::run_variants`).
    frames: 1,
    warmup: 1,
    rounds: 3,
};

/// Defaults when data sets are named on the command line: the papers' setting (the 14 fixed
/// viewpoints of the HAVS tables at 512×512).
pub const STANDARD_VIEWPOINTS: &str = "14";
pub const STANDARD_RESOLUTION: u32 = 512;
pub const STANDARD_FRAMES: u32 = 10;
pub const STANDARD_WARMUP: u32 = 2;
pub const STANDARD_ROUNDS: u32 = 1;

/// `14` (or `fixed`): the 14 fixed viewpoints; `axes` (6) or `diagonals` (8); `orbit:N`: N
/// frames around the up axis; or a comma-separated list of fixed viewpoint names (`+x,-y,+x+y-z`).
pub fn parse_viewpoints(spec: &str) -> anyhow::Result<Vec<Viewpoint>> {
    let spec = spec.trim();
    let fixed = fixed_viewpoints();
    match spec {
        "14" | "fixed" | "all" => return Ok(fixed),
        "axes" | "6" => return Ok(fixed[..6].to_vec()),
        "diagonals" | "8" => return Ok(fixed[6..].to_vec()),
        _ => {}
    }
    if let Some(n) = spec.strip_prefix("orbit:") {
        let n: usize = n.parse().map_err(|_| {
            anyhow::anyhow!("--viewpoints {spec:?}: orbit:N needs a whole number of frames")
        })?;
        if n == 0 || n > 100_000 {
            anyhow::bail!("--viewpoints {spec:?}: the orbit needs 1 to 100000 frames");
        }
        return Ok(orbit_viewpoints(n));
    }
    let mut out = vec![];
    for name in spec.split(',').map(str::trim).filter(|s| !s.is_empty()) {
        match fixed.iter().find(|v| v.name == name) {
            Some(v) => out.push(v.clone()),
            None => anyhow::bail!(
                "--viewpoints: unknown viewpoint {name:?}; use 14, axes, diagonals, orbit:N or names among {}",
                fixed.iter().map(|v| v.name.as_str()).collect::<Vec<_>>().join(",")
            ),
        }
    }
    if out.is_empty() {
        anyhow::bail!("--viewpoints is empty");
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn viewpoint_specs() {
        assert_eq!(parse_viewpoints("14").unwrap().len(), 14);
        assert_eq!(parse_viewpoints("axes").unwrap().len(), 6);
        assert_eq!(parse_viewpoints("orbit:36").unwrap().len(), 36);
        let v = parse_viewpoints(DEFAULT_SUITE.viewpoints).unwrap();
        assert_eq!(v.len(), 3);
        assert_eq!(v[1].name, "+x+y+z");
        assert!(parse_viewpoints("orbit:x").is_err());
        assert!(parse_viewpoints("orbit:0").is_err());
        assert!(parse_viewpoints("+w")
            .unwrap_err()
            .to_string()
            .contains("unknown viewpoint"));
    }
}
