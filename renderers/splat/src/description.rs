//! What the harness knows of the splatter without building it (see
//! [`render_core::description`]).

use render_core::{
    AlgorithmDescription, Hue, Origin, Param, Renderer, Settings, Tolerance, ValueKind,
};

use crate::{Buckets, GpuSort, Splat, SplatSettings};

pub static DESCRIPTION: AlgorithmDescription = AlgorithmDescription {
    name: "splat",
    title: "Sheet-buffered splatting with CPU or GPU buckets (Grau & Tost 2007)",
    origin: Origin::Paper("splat"),
    params: &[
        Param {
            key: "buckets",
            kind: ValueKind::Text,
            meaning: "where voxels are bucketed into slabs: cpu or gpu",
            section: "§3, Table 1",
        },
        Param {
            key: "sort",
            kind: ValueKind::Text,
            meaning: "the bucket sort: cpu-radix (cpu buckets), bitonic or radix (gpu buckets)",
            section: "§3.2",
        },
        Param {
            key: "radius",
            kind: ValueKind::Text,
            meaning: "kernel radius in grid spacings",
            section: "§2",
        },
        Param {
            key: "slab",
            kind: ValueKind::Text,
            meaning: "slab thickness in grid spacings",
            section: "§2 (sheet buffer)",
        },
        Param {
            key: "footprint",
            kind: ValueKind::Text,
            meaning: "footprint slice texels per side x slices per slab",
            section: "§2",
        },
        Param {
            key: "grid",
            kind: ValueKind::Int,
            meaning: "grid points along the longest side when a tet mesh is resampled",
            section: "ours (the paper splats voxel data)",
        },
        Param {
            key: "brick",
            kind: ValueKind::Text,
            meaning: "largest brick in voxels, or auto (one storage binding)",
            section: "ours (storage binding limits)",
        },
        Param {
            key: "ese",
            kind: ValueKind::Text,
            meaning: "early splat elimination behind opaque pixels (on/off)",
            section: "§3.3",
        },
        Param {
            key: "misalign",
            kind: ValueKind::Int,
            meaning: "a perturbation, not a configuration: every other brick drawn this many grid spacings off along x (the positive control of the bricks' image claim)",
            section: "ours (positive control of §4's claim)",
        },
    ],
    // The paper's pair (Table 1): CPU and GPU buckets.
    default_grid: || {
        [
            SplatSettings {
                buckets: Buckets::Cpu,
                ..Default::default()
            },
            SplatSettings::default(),
        ]
        .iter()
        .map(settings_of)
        .collect()
    },
    full_grid,
    build: |s| Ok(Box::new(Splat::new(from_settings(s)?)) as Box<dyn Renderer>),
    hue: Hue::Magentas,
    tolerance,
    counters: &[
        "splat_fragments",
        "fragments",
        "triangles",
        "cpu_sort_keys",
        "gpu_sort_keys",
    ],
    nondeterministic_counters: render_core::description::all_counters_exact,
    deterministic: render_core::description::always_deterministic,
    gpu_layouts: crate::gpu_layouts,
    counter_evidence: &[],
    perturbations: &["misalign"],
};

fn full_grid() -> Vec<Settings> {
    let mut out = vec![];
    for buckets in [Buckets::Cpu, Buckets::Gpu] {
        let sorts: &[GpuSort] = match buckets {
            Buckets::Cpu => &[GpuSort::Bitonic],
            Buckets::Gpu => &[GpuSort::Bitonic, GpuSort::Radix],
        };
        for &sort in sorts {
            for (radius, slab) in [(2.0, 1.0), (2.0, 0.5), (1.5, 1.5)] {
                for grid in [32, 64, 128] {
                    for ese in [true, false] {
                        for brick in [None, Some(1_000_000)] {
                            out.push(settings_of(&SplatSettings {
                                buckets,
                                sort,
                                radius,
                                slab,
                                grid,
                                ese,
                                brick,
                                ..Default::default()
                            }));
                        }
                    }
                }
            }
        }
    }
    // The positive control of the bricks' claim: the bricked GPU variant with every other
    // brick one voxel off.
    out.push(settings_of(&SplatSettings {
        brick: Some(1_000_000),
        misalign: 1,
        ..Default::default()
    }));
    out
}

pub(crate) fn settings_of(s: &SplatSettings) -> Settings {
    let settings = Settings::new()
        .with(
            "buckets",
            match s.buckets {
                Buckets::Cpu => "cpu",
                Buckets::Gpu => "gpu",
            },
        )
        .with(
            "sort",
            match (s.buckets, s.sort) {
                (Buckets::Cpu, _) => "cpu-radix",
                (_, GpuSort::Bitonic) => "bitonic",
                (_, GpuSort::Radix) => "radix",
            },
        )
        .with("radius", format!("{}", s.radius))
        .with("slab", format!("{}", s.slab))
        .with("footprint", format!("{}x{}", s.footprint, s.subslices))
        .with("grid", s.grid)
        .with(
            "brick",
            s.brick.map_or("auto".to_string(), |b| b.to_string()),
        )
        .with("ese", s.ese);
    // A perturbation is written only where set: every other variant keeps its settings.
    if s.misalign > 0 {
        settings.with("misalign", i64::from(s.misalign))
    } else {
        settings
    }
}

/// The typed settings of a variant.
pub fn from_settings(s: &Settings) -> anyhow::Result<SplatSettings> {
    let number = |key: &str| -> anyhow::Result<f64> {
        let t = s.require_text(key)?;
        t.parse()
            .map_err(|_| anyhow::anyhow!("splat: {key}={t} is not a number"))
    };
    let buckets = match s.require_text("buckets")?.as_str() {
        "cpu" => Buckets::Cpu,
        "gpu" => Buckets::Gpu,
        v => anyhow::bail!("splat: buckets={v} is neither cpu nor gpu"),
    };
    let sort = match (buckets, s.require_text("sort")?.as_str()) {
        (Buckets::Cpu, "cpu-radix") | (Buckets::Gpu, "bitonic") => GpuSort::Bitonic,
        (Buckets::Gpu, "radix") => GpuSort::Radix,
        (_, v) => anyhow::bail!(
            "splat: sort={v} does not go with buckets={}",
            s.require_text("buckets")?
        ),
    };
    let footprint = s.require_text("footprint")?;
    let (texels, slices) = footprint
        .split_once('x')
        .and_then(|(a, b)| Some((a.parse().ok()?, b.parse().ok()?)))
        .ok_or_else(|| anyhow::anyhow!("splat: footprint={footprint} is not TEXELSxSLICES"))?;
    let brick = match s.require_text("brick")?.as_str() {
        "auto" => None,
        b => Some(
            b.parse()
                .map_err(|_| anyhow::anyhow!("splat: brick={b} is neither auto nor a count"))?,
        ),
    };
    let grid = s.require_int("grid")?;
    let misalign = match s.get("misalign") {
        None => 0,
        Some(_) => {
            let m = s.require_int("misalign")?;
            u32::try_from(m).map_err(|_| anyhow::anyhow!("splat: misalign={m} is negative"))?
        }
    };
    Ok(SplatSettings {
        buckets,
        sort,
        radius: number("radius")?,
        slab: number("slab")?,
        footprint: texels,
        subslices: slices,
        grid: usize::try_from(grid)
            .map_err(|_| anyhow::anyhow!("splat: grid={grid} is negative"))?,
        brick,
        ese: s.require_switch("ese")?,
        misalign,
    })
}

/// Measured on the check scene (`tests/vs_reference.rs`, lavapipe): 40.4 dB with either bucket
/// variant (the mesh resampled to a 32-point grid and splatted with a smooth kernel); 3 dB
/// margin.
fn tolerance(_: &Settings) -> Tolerance {
    Tolerance {
        min_psnr_db: 37.0,
        why: "a resampled grid and a smooth kernel: 40.4 dB measured, 3 dB margin",
    }
}
