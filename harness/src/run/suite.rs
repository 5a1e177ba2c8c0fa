//! The embedded default suite (`tetbench run` with no arguments) and the defaults when data
//! sets are named (`--viewpoints` is parsed by [`crate::results::Viewpoints`]).

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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::results::Viewpoints;

    #[test]
    fn the_default_viewpoints_parse() {
        let v: Viewpoints = DEFAULT_SUITE.viewpoints.parse().unwrap();
        assert_eq!(v.names(), ["+x", "+x+y+z", "-x+y-z"]);
        assert_eq!(STANDARD_VIEWPOINTS.parse::<Viewpoints>().unwrap().len(), 14);
    }
}
