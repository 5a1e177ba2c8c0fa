//! What a result was measured on: CPU, memory, OS, host, load, GPU adapter, and what measured
//! it: tetbench's version, commit, dirty flag, build profile and compiler, all embedded when
//! the binary was built (`harness/build.rs`), so a copied or stale binary still says what it
//! is. Recorded once per results file (and adapter/backend again in every row).

use std::process::Command;
use std::time::{SystemTime, UNIX_EPOCH};

use render_core::AdapterDescription;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct MachineInfo {
    pub cpu_model: String,
    /// Logical cores available to this process.
    pub cpu_cores: usize,
    pub memory_bytes: Option<u64>,
    pub os: String,
    pub kernel: Option<String>,
    pub arch: String,
    #[schemars(with = "Option<AdapterSchema>")]
    pub adapter: Option<AdapterDescription>,
    /// The commit the binary was built from (`None`: built outside a git checkout).
    pub git_commit: Option<String>,
    /// Whether tracked files differed from that commit when the binary was built.
    pub git_dirty: Option<bool>,
    /// `release` or `debug` (`None` in files written before it was recorded).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub build_profile: Option<String>,
    /// `rustc --version` of the build.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rustc_version: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub host_name: Option<String>,
    /// The 1-minute load average when the run started and when it finished (Linux; a loaded
    /// machine explains a slow run).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub load_average_start: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub load_average_end: Option<f64>,
    /// When the run started, ISO 8601 UTC.
    pub date_utc: String,
    pub tetbench_version: String,
    /// The backend's micro-benchmark figures (`tetbench calibrate`); `None` with
    /// `--no-calibrate` and in files of schema 1.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub calibration: Option<Calibration>,
}

/// [`AdapterDescription`]'s fields for the JSON Schema (render-core does not depend on
/// schemars); `adapter_schema_mirrors_render_core` keeps the two in step.
#[derive(JsonSchema)]
#[allow(dead_code)]
#[schemars(deny_unknown_fields)]
struct AdapterSchema {
    name: String,
    backend: String,
    device_type: String,
    driver: String,
    driver_info: String,
}

impl MachineInfo {
    /// Gathers everything but the adapter (set by the caller once the GPU is opened).
    pub fn collect() -> MachineInfo {
        let built = |s: &'static str| (!s.is_empty()).then(|| s.to_string());
        MachineInfo {
            cpu_model: cpu_model().unwrap_or_else(|| "unknown".into()),
            cpu_cores: std::thread::available_parallelism()
                .map(|n| n.get())
                .unwrap_or(1),
            memory_bytes: memory_bytes(),
            os: os_name(),
            kernel: std::fs::read_to_string("/proc/sys/kernel/osrelease")
                .ok()
                .map(|s| s.trim().to_string()),
            arch: std::env::consts::ARCH.to_string(),
            adapter: None,
            git_commit: built(env!("TETBENCH_GIT_COMMIT")),
            git_dirty: built(env!("TETBENCH_GIT_DIRTY")).map(|d| d == "true"),
            build_profile: built(env!("TETBENCH_BUILD_PROFILE")),
            rustc_version: built(env!("TETBENCH_RUSTC_VERSION")),
            host_name: Some(host_name()),
            load_average_start: load_average(),
            load_average_end: None,
            date_utc: iso8601_utc(SystemTime::now()),
            tetbench_version: env!("CARGO_PKG_VERSION").to_string(),
            calibration: None,
        }
    }
}

/// This machine's name (`/proc/sys/kernel/hostname`, `$HOSTNAME`, `uname -n`), or `unknown`.
pub fn host_name() -> String {
    std::fs::read_to_string("/proc/sys/kernel/hostname")
        .ok()
        .map(|s| s.trim().to_string())
        .filter(|s| !s.is_empty())
        .or_else(|| std::env::var("HOSTNAME").ok().filter(|s| !s.is_empty()))
        .or_else(|| {
            let out = Command::new("uname").arg("-n").output().ok()?;
            let s = String::from_utf8_lossy(&out.stdout).trim().to_string();
            (!s.is_empty()).then_some(s)
        })
        .unwrap_or_else(|| "unknown".into())
}

/// The 1-minute load average (`/proc/loadavg`); `None` elsewhere.
pub fn load_average() -> Option<f64> {
    std::fs::read_to_string("/proc/loadavg")
        .ok()?
        .split_whitespace()
        .next()?
        .parse()
        .ok()
}

fn cpu_model() -> Option<String> {
    if let Ok(info) = std::fs::read_to_string("/proc/cpuinfo") {
        for key in ["model name", "Hardware", "Processor", "cpu model"] {
            if let Some(v) = info
                .lines()
                .filter_map(|l| l.split_once(':'))
                .find(|(k, _)| k.trim() == key)
                .map(|(_, v)| v.trim().to_string())
            {
                return Some(v);
            }
        }
    }
    // macOS and the BSDs.
    let out = Command::new("sysctl")
        .args(["-n", "machdep.cpu.brand_string"])
        .output()
        .ok()?;
    out.status
        .success()
        .then(|| String::from_utf8_lossy(&out.stdout).trim().to_string())
}

fn memory_bytes() -> Option<u64> {
    let info = std::fs::read_to_string("/proc/meminfo").ok();
    if let Some(info) = info {
        let line = info.lines().find(|l| l.starts_with("MemTotal:"))?;
        let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
        return Some(kib * 1024);
    }
    let out = Command::new("sysctl")
        .args(["-n", "hw.memsize"])
        .output()
        .ok()?;
    String::from_utf8_lossy(&out.stdout).trim().parse().ok()
}

fn os_name() -> String {
    if let Ok(rel) = std::fs::read_to_string("/etc/os-release") {
        if let Some(name) = rel.lines().find_map(|l| l.strip_prefix("PRETTY_NAME=")) {
            return name.trim_matches('"').to_string();
        }
    }
    std::env::consts::OS.to_string()
}

/// `YYYY-MM-DDTHH:MM:SSZ` (RFC 3339 in UTC, whole seconds; `humantime`). Times before 1970
/// (a clock set wrong) are written as the epoch.
pub fn iso8601_utc(t: SystemTime) -> String {
    humantime::format_rfc3339_seconds(t.max(UNIX_EPOCH)).to_string()
}

/// The backend's figures, stored in every run's machine record.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct Calibration {
    pub version: u32,
    pub adapter: String,
    pub driver: String,
    pub cpu_model: String,
    pub cpu_cores: usize,
    pub date_utc: String,
    /// Wall time the measurement took.
    pub seconds: f64,
    /// Sub-pixel triangles (no fragment) set up and rasterised per second.
    pub triangles_per_sec: f64,
    /// Blended fragments per second into `fill_format`.
    pub fill_fragments_per_sec: f64,
    pub fill_format: String,
    /// f32 FMA throughput, GFLOP/s (1 FMA = 2 FLOPs).
    pub compute_gflops: f64,
    /// Storage-to-storage copy, bytes read + bytes written per second.
    pub copy_bytes_per_sec: f64,
    /// `render_core::sort::radix_sort_indices`: the fastest of 2^14, 2^17 and 2^20 f32 keys.
    pub sort_keys_per_sec: f64,
    /// Steps of a walk through 144-byte cells (a dependent gather, four plane tests, one
    /// table lookup each), the ray caster's unit of work. 0 in calibrations made before it.
    #[serde(default)]
    pub ray_steps_per_sec: f64,
    /// Footprint pixels of the splatter's compute fill: a two-slice bilinear footprint lookup
    /// added with atomics into a fixed-point sheet, zero terms skipped: the fastest of square
    /// footprints of 4–32 pixels a side with a dense and a ball-shaped table; 0 in calibrations
    /// made before it.
    #[serde(default)]
    pub splat_fragments_per_sec: f64,
    /// render-core's GPU radix sort: the fastest of 2^16 and 2^18 f32 keys. 0 in calibrations made before it.
    #[serde(default)]
    pub gpu_sort_keys_per_sec: f64,
    /// Tet classifications (projection, orientation tests, diagonal intersection: the part of
    /// a projected-tetrahedra classification every variant does) per second, one compute
    /// invocation per tet. 0 in calibrations made before it.
    #[serde(default)]
    pub tet_classifications_per_sec: f64,
    /// Rasterising triangles that cover pixels (right triangles with 4- and 16-pixel legs,
    /// blended into `fill_format`), fitted as a cost per triangle plus a cost per fragment:
    /// seconds per triangle. 0 in calibrations made before it.
    #[serde(default)]
    pub raster_seconds_per_triangle: f64,
    /// The fit's seconds per fragment (see `raster_seconds_per_triangle`).
    #[serde(default)]
    pub raster_seconds_per_fragment: f64,
}

/// One figure of a [`Calibration`]: a rate (larger is faster) or a cost (smaller is faster).
/// The calibration's probes, the control measured beside every run's rows and the roofline's
/// pricing all name figures by this type.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize, JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum Figure {
    TrianglesPerSec,
    FillFragmentsPerSec,
    ComputeGflops,
    CopyBytesPerSec,
    SortKeysPerSec,
    RayStepsPerSec,
    SplatFragmentsPerSec,
    GpuSortKeysPerSec,
    TetClassificationsPerSec,
    RasterSecondsPerTriangle,
    RasterSecondsPerFragment,
}

impl Figure {
    pub const ALL: [Figure; 11] = [
        Figure::TrianglesPerSec,
        Figure::FillFragmentsPerSec,
        Figure::ComputeGflops,
        Figure::CopyBytesPerSec,
        Figure::SortKeysPerSec,
        Figure::RayStepsPerSec,
        Figure::SplatFragmentsPerSec,
        Figure::GpuSortKeysPerSec,
        Figure::TetClassificationsPerSec,
        Figure::RasterSecondsPerTriangle,
        Figure::RasterSecondsPerFragment,
    ];

    /// The field's name in `results.json` (and the calibration cache).
    pub fn name(self) -> &'static str {
        match self {
            Figure::TrianglesPerSec => "triangles_per_sec",
            Figure::FillFragmentsPerSec => "fill_fragments_per_sec",
            Figure::ComputeGflops => "compute_gflops",
            Figure::CopyBytesPerSec => "copy_bytes_per_sec",
            Figure::SortKeysPerSec => "sort_keys_per_sec",
            Figure::RayStepsPerSec => "ray_steps_per_sec",
            Figure::SplatFragmentsPerSec => "splat_fragments_per_sec",
            Figure::GpuSortKeysPerSec => "gpu_sort_keys_per_sec",
            Figure::TetClassificationsPerSec => "tet_classifications_per_sec",
            Figure::RasterSecondsPerTriangle => "raster_seconds_per_triangle",
            Figure::RasterSecondsPerFragment => "raster_seconds_per_fragment",
        }
    }

    /// Whether a larger value is a faster machine (a rate); otherwise it is a cost.
    pub fn is_rate(self) -> bool {
        !matches!(
            self,
            Figure::RasterSecondsPerTriangle | Figure::RasterSecondsPerFragment
        )
    }

    /// The figure as a speed: the rate, or 1 / the cost (0 where not measured). Ratios of
    /// speeds compare two measurements of a figure the same way for rates and costs.
    pub fn speed(self, value: f64) -> f64 {
        match (self.is_rate(), value > 0.0) {
            (_, false) => 0.0,
            (true, true) => value,
            (false, true) => 1.0 / value,
        }
    }

    /// A figure's value at `speed` (the inverse of [`Figure::speed`]).
    pub fn from_speed(self, speed: f64) -> f64 {
        self.speed(speed)
    }

    pub fn get(self, c: &Calibration) -> f64 {
        match self {
            Figure::TrianglesPerSec => c.triangles_per_sec,
            Figure::FillFragmentsPerSec => c.fill_fragments_per_sec,
            Figure::ComputeGflops => c.compute_gflops,
            Figure::CopyBytesPerSec => c.copy_bytes_per_sec,
            Figure::SortKeysPerSec => c.sort_keys_per_sec,
            Figure::RayStepsPerSec => c.ray_steps_per_sec,
            Figure::SplatFragmentsPerSec => c.splat_fragments_per_sec,
            Figure::GpuSortKeysPerSec => c.gpu_sort_keys_per_sec,
            Figure::TetClassificationsPerSec => c.tet_classifications_per_sec,
            Figure::RasterSecondsPerTriangle => c.raster_seconds_per_triangle,
            Figure::RasterSecondsPerFragment => c.raster_seconds_per_fragment,
        }
    }

    pub fn set(self, c: &mut Calibration, value: f64) {
        *match self {
            Figure::TrianglesPerSec => &mut c.triangles_per_sec,
            Figure::FillFragmentsPerSec => &mut c.fill_fragments_per_sec,
            Figure::ComputeGflops => &mut c.compute_gflops,
            Figure::CopyBytesPerSec => &mut c.copy_bytes_per_sec,
            Figure::SortKeysPerSec => &mut c.sort_keys_per_sec,
            Figure::RayStepsPerSec => &mut c.ray_steps_per_sec,
            Figure::SplatFragmentsPerSec => &mut c.splat_fragments_per_sec,
            Figure::GpuSortKeysPerSec => &mut c.gpu_sort_keys_per_sec,
            Figure::TetClassificationsPerSec => &mut c.tet_classifications_per_sec,
            Figure::RasterSecondsPerTriangle => &mut c.raster_seconds_per_triangle,
            Figure::RasterSecondsPerFragment => &mut c.raster_seconds_per_fragment,
        } = value;
    }
}

impl std::fmt::Display for Figure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl Calibration {
    /// Figure by figure the faster of `self` and `other` (two measurements of the same
    /// backend): the larger rate, the smaller cost where both were measured (0 = not
    /// measured). The rest (date, seconds) is `self`'s. For the rasterisation fit, each of its
    /// two costs the smaller: the bound at any triangle size is then at most either fit's.
    pub fn peak_with(&self, other: &Calibration) -> Calibration {
        let mut out = self.clone();
        for figure in Figure::ALL {
            let speed = figure
                .speed(figure.get(self))
                .max(figure.speed(figure.get(other)));
            figure.set(&mut out, figure.from_speed(speed));
        }
        out
    }

    /// The lines `tetbench calibrate` prints.
    pub fn describe(&self) -> String {
        format!(
            "adapter           {} ({})\ncpu               {} ({} cores)\n\
             triangle setup    {:.2} M triangles/s (sub-pixel, no fragments)\n\
             fill rate         {:.1} M fragments/s (blended, {})\n\
             compute           {:.2} GFLOP/s (f32 FMA)\n\
             storage copy      {:.2} GB/s (read + write)\n\
             CPU radix sort    {:.1} M keys/s (best of 2^14, 2^17, 2^20 f32 keys)\n\
             GPU radix sort    {:.1} M keys/s (best of 2^16, 2^18 f32 keys)\n\
             ray steps         {:.2} M steps/s (144-byte cell walk)\n\
             splat fill        {:.1} M fragments/s (compute footprint lookup, best of 4-32 px)\n\
             classification    {:.1} M tets/s (projection, orientation tests, diagonals)\n\
             rasterisation     {:.0} ns/triangle + {:.2} ns/fragment (covering triangles, blended)\n\
             measured in {:.1} s on {}",
            self.adapter,
            self.driver,
            self.cpu_model,
            self.cpu_cores,
            self.triangles_per_sec * 1e-6,
            self.fill_fragments_per_sec * 1e-6,
            self.fill_format,
            self.compute_gflops,
            self.copy_bytes_per_sec * 1e-9,
            self.sort_keys_per_sec * 1e-6,
            self.gpu_sort_keys_per_sec * 1e-6,
            self.ray_steps_per_sec * 1e-6,
            self.splat_fragments_per_sec * 1e-6,
            self.tet_classifications_per_sec * 1e-6,
            self.raster_seconds_per_triangle * 1e9,
            self.raster_seconds_per_fragment * 1e9,
            self.seconds,
            self.date_utc
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::Duration;

    #[test]
    fn iso_dates() {
        assert_eq!(iso8601_utc(UNIX_EPOCH), "1970-01-01T00:00:00Z");
        assert_eq!(
            iso8601_utc(UNIX_EPOCH - Duration::from_secs(5)),
            "1970-01-01T00:00:00Z"
        );
        // 2000-02-29T12:34:56Z (a leap day in a century leap year).
        assert_eq!(
            iso8601_utc(UNIX_EPOCH + Duration::from_secs(951_827_696)),
            "2000-02-29T12:34:56Z"
        );
        assert_eq!(
            iso8601_utc(UNIX_EPOCH + Duration::from_secs(1_798_761_599)),
            "2026-12-31T23:59:59Z"
        );
    }

    #[test]
    fn collects_something_sane() {
        let m = MachineInfo::collect();
        assert!(m.cpu_cores >= 1);
        assert!(!m.os.is_empty());
        assert_eq!(m.date_utc.len(), 20);
        assert!(!m.host_name.unwrap().is_empty());
    }

    #[test]
    fn adapter_schema_mirrors_render_core() {
        let a = AdapterDescription {
            name: String::new(),
            backend: String::new(),
            device_type: String::new(),
            driver: String::new(),
            driver_info: String::new(),
        };
        let fields: Vec<String> = serde_json::to_value(a)
            .unwrap()
            .as_object()
            .unwrap()
            .keys()
            .cloned()
            .collect();
        let schema = serde_json::to_value(schemars::schema_for!(AdapterSchema)).unwrap();
        let mut mirrored: Vec<String> = schema["properties"]
            .as_object()
            .unwrap()
            .keys()
            .cloned()
            .collect();
        let mut fields = fields;
        fields.sort();
        mirrored.sort();
        assert_eq!(fields, mirrored);
    }

    /// The provenance comes from the build, not from the directory the binary runs in: the
    /// test binary is built from this checkout, so it knows its commit, profile and compiler.
    #[test]
    fn provenance_is_embedded_at_build_time() {
        let m = MachineInfo::collect();
        let commit = m.git_commit.expect("built from a git checkout");
        assert_eq!(commit.len(), 40, "{commit}");
        assert!(m.git_dirty.is_some());
        assert!(["debug", "release"].contains(&m.build_profile.as_deref().unwrap()));
        assert!(m.rustc_version.unwrap().starts_with("rustc "));
    }
}
