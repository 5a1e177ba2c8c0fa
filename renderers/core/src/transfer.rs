//! Transfer functions: piecewise-linear chromaticity c(s) and extinction κ(s) over the
//! normalised scalar s ∈ [0, 1].
//!
//! κ is measured per unit of the mesh's bounding-box diagonal, so one transfer function suits
//! every data set (a ray through the whole box with κ = 1 keeps e⁻¹ of the light behind it).

use serde::{Deserialize, Serialize};

/// A control point of a piecewise-linear function on [0, 1].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ColorPoint {
    pub s: f64,
    pub rgb: [f64; 3],
}

#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct KappaPoint {
    pub s: f64,
    pub kappa: f64,
}

/// Piecewise-linear c(s) and κ(s); both clamp outside their first and last points.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TransferFunction {
    pub name: String,
    /// Sorted by `s`, at least one point.
    pub color: Vec<ColorPoint>,
    /// Sorted by `s`, at least one point.
    pub kappa: Vec<KappaPoint>,
}

impl TransferFunction {
    /// Chromaticity at normalised scalar `s`.
    pub fn color_at(&self, s: f64) -> [f64; 3] {
        let pts = &self.color;
        let i = pts.partition_point(|p| p.s <= s);
        if i == 0 {
            return pts[0].rgb;
        }
        if i == pts.len() {
            return pts[pts.len() - 1].rgb;
        }
        let (a, b) = (pts[i - 1], pts[i]);
        let t = if b.s > a.s {
            (s - a.s) / (b.s - a.s)
        } else {
            0.0
        };
        [0, 1, 2].map(|k| a.rgb[k] + t * (b.rgb[k] - a.rgb[k]))
    }

    /// Extinction at normalised scalar `s`, per unit of the bounding-box diagonal.
    pub fn kappa_at(&self, s: f64) -> f64 {
        let pts = &self.kappa;
        let i = pts.partition_point(|p| p.s <= s);
        if i == 0 {
            return pts[0].kappa;
        }
        if i == pts.len() {
            return pts[pts.len() - 1].kappa;
        }
        let (a, b) = (pts[i - 1], pts[i]);
        let t = if b.s > a.s {
            (s - a.s) / (b.s - a.s)
        } else {
            0.0
        };
        a.kappa + t * (b.kappa - a.kappa)
    }

    /// The lookup table shaders sample: `entries` rows of (rgb = c(s), a = κ(s) per length
    /// unit) at s = i / (entries − 1).
    pub fn rgb_kappa_table(&self, entries: usize) -> Vec<[f32; 4]> {
        (0..entries)
            .map(|i| {
                let s = i as f64 / (entries.max(2) - 1) as f64;
                let c = self.color_at(s);
                [
                    c[0] as f32,
                    c[1] as f32,
                    c[2] as f32,
                    self.kappa_at(s) as f32,
                ]
            })
            .collect()
    }

    /// Every scalar value where c or κ has a kink, sorted and deduplicated: exact integration
    /// splits a segment there so that each piece is linear in s.
    pub fn breakpoints(&self) -> Vec<f64> {
        let mut b: Vec<f64> = self
            .color
            .iter()
            .map(|p| p.s)
            .chain(self.kappa.iter().map(|p| p.s))
            .collect();
        b.sort_by(|x, y| x.total_cmp(y));
        b.dedup();
        b
    }

    /// The largest κ anywhere (bounds opacity per unit length).
    pub fn max_kappa(&self) -> f64 {
        self.kappa.iter().map(|p| p.kappa).fold(0.0, f64::max)
    }
}

/// Why a transfer function was refused.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum TransferError {
    #[error("transfer function '{name}' has no {what} points")]
    Empty { name: String, what: &'static str },
    #[error("transfer function '{name}': {what} point {index} has a non-finite value")]
    NonFinite {
        name: String,
        what: &'static str,
        index: usize,
    },
    #[error("transfer function '{name}': {what} points are not sorted by s (point {index})")]
    Unsorted {
        name: String,
        what: &'static str,
        index: usize,
    },
    #[error("transfer function '{name}': extinction {value} at point {index} is negative")]
    NegativeKappa {
        name: String,
        index: usize,
        value: f64,
    },
    #[error("transfer function '{name}': colour {value} at point {index} is negative")]
    NegativeColor {
        name: String,
        index: usize,
        value: f64,
    },
}

/// Names accepted by [`TransferFunction::preset`], the default first.
pub const PRESET_NAMES: [&str; 3] = ["low-opacity", "high-opacity", "zero-floor"];

/// Default scale K of the ParaView opacity mapping κ = o·K (see
/// [`TransferFunction::from_paraview_json`]): K is the bounding-box diagonal over ParaView's
/// "Scalar Opacity Unit Distance", here one tenth of the diagonal.
pub const PARAVIEW_OPACITY_SCALE: f64 = 10.0;

/// Linear pieces each non-linear ParaView opacity interval (midpoint ≠ ½ or sharpness ≠ 0) is
/// sampled into, so the function stays piecewise linear for exact pre-integration.
const PARAVIEW_CURVE_PIECES: usize = 16;

/// A rainbow from blue through cyan, green and yellow to red, as in the HAVS paper's figures.
const RAINBOW: [(f64, [f64; 3]); 5] = [
    (0.0, [0.10, 0.15, 0.90]),
    (0.25, [0.05, 0.75, 0.90]),
    (0.5, [0.15, 0.85, 0.20]),
    (0.75, [0.95, 0.85, 0.10]),
    (1.0, [0.95, 0.15, 0.05]),
];

impl TransferFunction {
    /// A built-in transfer function by name (see [`PRESET_NAMES`]).
    ///
    /// * `low-opacity` (the default for runs): the HAVS tables were measured with a low-opacity
    ///   map, so that most of the volume is seen through and every fragment matters. κ rises
    ///   from 0.2 to 5 per diagonal: a ray crossing half the box at the median κ keeps about
    ///   half of the light behind it.
    /// * `high-opacity`: the same colours with ten times the extinction (2 … 50 per diagonal):
    ///   rays saturate within a few cells, which exercises early ray termination.
    /// * `zero-floor`: `low-opacity` with κ(0) = 0, so a voxel of value 0 (the scalar range's
    ///   minimum) is empty: the splatter's effective voxels are then exactly the non-zero ones,
    ///   which is how the Table 1 stand-ins of Grau & Tost are counted (§5).
    pub fn preset(name: &str) -> Option<TransferFunction> {
        let (scale, floor) = match name {
            "low-opacity" => (1.0, 0.2),
            "high-opacity" => (10.0, 0.2),
            "zero-floor" => (1.0, 0.0),
            _ => return None,
        };
        let kappa_low = [
            (0.0, floor),
            (0.25, 0.8),
            (0.5, 1.5),
            (0.75, 3.0),
            (1.0, 5.0),
        ];
        Some(TransferFunction {
            name: name.to_string(),
            color: RAINBOW
                .iter()
                .map(|&(s, rgb)| ColorPoint { s, rgb })
                .collect(),
            kappa: kappa_low
                .iter()
                .map(|&(s, k)| KappaPoint {
                    s,
                    kappa: k * scale,
                })
                .collect(),
        })
    }

    /// Checks the invariants every integrator relies on: at least one point of each kind, all
    /// values finite, points sorted by `s` (equal `s` allowed: a step), κ ≥ 0, colours ≥ 0.
    pub fn validate(&self) -> Result<(), TransferError> {
        let name = || self.name.clone();
        if self.color.is_empty() {
            return Err(TransferError::Empty {
                name: name(),
                what: "colour",
            });
        }
        if self.kappa.is_empty() {
            return Err(TransferError::Empty {
                name: name(),
                what: "extinction",
            });
        }
        for (i, p) in self.color.iter().enumerate() {
            if !p.s.is_finite() || p.rgb.iter().any(|v| !v.is_finite()) {
                return Err(TransferError::NonFinite {
                    name: name(),
                    what: "colour",
                    index: i,
                });
            }
            if let Some(&v) = p.rgb.iter().find(|v| **v < 0.0) {
                return Err(TransferError::NegativeColor {
                    name: name(),
                    index: i,
                    value: v,
                });
            }
            if i > 0 && p.s < self.color[i - 1].s {
                return Err(TransferError::Unsorted {
                    name: name(),
                    what: "colour",
                    index: i,
                });
            }
        }
        for (i, p) in self.kappa.iter().enumerate() {
            if !p.s.is_finite() || !p.kappa.is_finite() {
                return Err(TransferError::NonFinite {
                    name: name(),
                    what: "extinction",
                    index: i,
                });
            }
            if p.kappa < 0.0 {
                return Err(TransferError::NegativeKappa {
                    name: name(),
                    index: i,
                    value: p.kappa,
                });
            }
            if i > 0 && p.s < self.kappa[i - 1].s {
                return Err(TransferError::Unsorted {
                    name: name(),
                    what: "extinction",
                    index: i,
                });
            }
        }
        Ok(())
    }

    /// A preset name (see [`PRESET_NAMES`]) or a file: a ParaView colormap preset (`.json`, see
    /// [`TransferFunction::from_paraview_json`]) or this type serialised as JSON (an object with
    /// `color` and `kappa`). Errors name the file and what was wrong.
    pub fn load(name_or_path: &str) -> anyhow::Result<TransferFunction> {
        if let Some(tf) = TransferFunction::preset(name_or_path) {
            return Ok(tf);
        }
        let path = std::path::Path::new(name_or_path);
        if !path.is_file() {
            anyhow::bail!(
                "transfer function '{name_or_path}' is neither a preset ({}) nor a readable file",
                PRESET_NAMES.join(", ")
            );
        }
        TransferFunction::from_paraview_json(path)
    }

    /// Reads a ParaView colormap preset with the default opacity scale
    /// [`PARAVIEW_OPACITY_SCALE`].
    pub fn from_paraview_json(path: &std::path::Path) -> anyhow::Result<TransferFunction> {
        TransferFunction::from_paraview_json_scaled(path, PARAVIEW_OPACITY_SCALE)
    }

    /// Reads a ParaView colormap preset: a JSON array of presets (the first one with
    /// `RGBPoints` is used) or a single preset object. `RGBPoints` is `[x, r, g, b, …]`;
    /// the optional `Points` is the opacity function `[x, o, midpoint, sharpness, …]`.
    /// x is rescaled to [0, 1] over the range of the colour points.
    ///
    /// Colours are interpolated linearly in RGB (ParaView may interpolate in Lab or the
    /// diverging Msh space; our optical model is piecewise linear in RGB, which exact
    /// pre-integration needs). Opacity o becomes extinction κ = o·K per diagonal, with
    /// K = `opacity_scale`: VTK's unstructured-grid mappers, which ParaView uses for
    /// tetrahedral meshes (projected tetra, ZSweep, Bunyk ray casting), read a scalar opacity
    /// as the attenuation o / u per world unit, u the "Scalar Opacity Unit Distance"; with
    /// K = diagonal / u the two attenuate alike, and κ stays linear wherever o is, as it does in
    /// VTK. Intervals with ParaView's non-linear midpoint/sharpness shape (vtkPiecewiseFunction)
    /// are sampled into 16 linear pieces; κ is linear between the resulting points. Without
    /// `Points`, opacity ramps linearly from 0 to 1.
    ///
    /// A file holding this type serialised (object with `color` and `kappa`) is accepted too.
    pub fn from_paraview_json_scaled(
        path: &std::path::Path,
        opacity_scale: f64,
    ) -> anyhow::Result<TransferFunction> {
        let text = std::fs::read_to_string(path).map_err(|e| {
            anyhow::anyhow!("cannot read transfer function file {}: {e}", path.display())
        })?;
        let value: serde_json::Value = serde_json::from_str(&text).map_err(|e| {
            anyhow::anyhow!(
                "transfer function file {} is not valid JSON: {e}",
                path.display()
            )
        })?;
        let stem = path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        let tf = parse_transfer_json(&value, &stem, opacity_scale)
            .map_err(|e| anyhow::anyhow!("transfer function file {}: {e}", path.display()))?;
        tf.validate()
            .map_err(|e| anyhow::anyhow!("transfer function file {}: {e}", path.display()))?;
        Ok(tf)
    }
}

/// Parses either ParaView preset JSON or a serialised [`TransferFunction`].
fn parse_transfer_json(
    value: &serde_json::Value,
    stem: &str,
    opacity_scale: f64,
) -> Result<TransferFunction, String> {
    use serde_json::Value;
    if let Value::Object(m) = value {
        if m.contains_key("color") && m.contains_key("kappa") {
            return serde_json::from_value(value.clone())
                .map_err(|e| format!("not a transfer function: {e}"));
        }
    }
    let preset = match value {
        Value::Array(items) => items
            .iter()
            .find(|v| v.get("RGBPoints").is_some())
            .ok_or_else(|| "no preset with RGBPoints in the array".to_string())?,
        Value::Object(_) => value,
        _ => return Err("expected a ParaView preset object or an array of them".into()),
    };
    let numbers = |key: &str| -> Result<Option<Vec<f64>>, String> {
        match preset.get(key) {
            None | Some(Value::Null) => Ok(None),
            Some(Value::Array(a)) => a
                .iter()
                .enumerate()
                .map(|(i, v)| {
                    v.as_f64()
                        .ok_or_else(|| format!("{key}[{i}] is not a number"))
                })
                .collect::<Result<Vec<f64>, String>>()
                .map(Some),
            Some(_) => Err(format!("{key} is not an array")),
        }
    };
    let rgb = numbers("RGBPoints")?.ok_or_else(|| "preset has no RGBPoints".to_string())?;
    if rgb.is_empty() || rgb.len() % 4 != 0 {
        return Err(format!(
            "RGBPoints has {} numbers, expected a non-zero multiple of 4",
            rgb.len()
        ));
    }
    if let Some(i) = rgb.iter().position(|v| !v.is_finite()) {
        return Err(format!("RGBPoints[{i}] is not finite"));
    }
    let xs: Vec<f64> = rgb.chunks(4).map(|c| c[0]).collect();
    let (x0, x1) = (xs[0], xs[xs.len() - 1]);
    if let Some(i) = xs.windows(2).position(|w| w[1] < w[0]) {
        return Err(format!(
            "RGBPoints x values are not sorted (point {})",
            i + 1
        ));
    }
    let span = x1 - x0;
    let rescale = |x: f64| {
        if span > 0.0 {
            ((x - x0) / span).clamp(0.0, 1.0)
        } else {
            0.0
        }
    };
    let color: Vec<ColorPoint> = rgb
        .chunks(4)
        .map(|c| ColorPoint {
            s: rescale(c[0]),
            rgb: [c[1], c[2], c[3]],
        })
        .collect();
    let kappa_of = |o: f64| o.max(0.0) * opacity_scale;
    let kappa = match numbers("Points")? {
        None => vec![
            KappaPoint {
                s: 0.0,
                kappa: kappa_of(0.0),
            },
            KappaPoint {
                s: 1.0,
                kappa: kappa_of(1.0),
            },
        ],
        Some(p) => {
            if p.is_empty() || p.len() % 4 != 0 {
                return Err(format!(
                    "Points has {} numbers, expected a non-zero multiple of 4",
                    p.len()
                ));
            }
            if let Some(i) = p.iter().position(|v| !v.is_finite()) {
                return Err(format!("Points[{i}] is not finite"));
            }
            let nodes: Vec<[f64; 4]> = p.chunks(4).map(|c| [c[0], c[1], c[2], c[3]]).collect();
            if let Some(i) = nodes.windows(2).position(|w| w[1][0] < w[0][0]) {
                return Err(format!("Points x values are not sorted (point {})", i + 1));
            }
            let mut out = vec![KappaPoint {
                s: rescale(nodes[0][0]),
                kappa: kappa_of(nodes[0][1]),
            }];
            for w in nodes.windows(2) {
                let ([xa, ya, mid, sharp], [xb, yb, _, _]) = (w[0], w[1]);
                let linear = (mid - 0.5).abs() < 1e-12 && sharp.abs() < 1e-12;
                let pieces = if linear || xb <= xa {
                    1
                } else {
                    PARAVIEW_CURVE_PIECES
                };
                for k in 1..=pieces {
                    let t = k as f64 / pieces as f64;
                    let o = if linear {
                        ya + t * (yb - ya)
                    } else {
                        paraview_curve(ya, yb, mid, sharp, t)
                    };
                    out.push(KappaPoint {
                        s: rescale(xa + t * (xb - xa)),
                        kappa: kappa_of(o),
                    });
                }
            }
            out
        }
    };
    let name = preset
        .get("Name")
        .and_then(|v| v.as_str())
        .map(str::to_string)
        .unwrap_or_else(|| stem.to_string());
    Ok(TransferFunction { name, color, kappa })
}

/// vtkPiecewiseFunction's shape between two nodes (values `ya`, `yb`) at fraction `t`: the
/// midpoint moves where the value is half-way, the sharpness bends the curve from linear (0)
/// through a Hermite curve with flattened tangents towards a step (1).
fn paraview_curve(ya: f64, yb: f64, mid: f64, sharp: f64, t: f64) -> f64 {
    let mid = mid.clamp(1e-5, 1.0 - 1e-5);
    let mut t = if t < mid {
        0.5 * t / mid
    } else {
        0.5 + 0.5 * (t - mid) / (1.0 - mid)
    };
    if sharp > 0.99 {
        return if t < 0.5 { ya } else { yb };
    }
    if sharp < 0.01 {
        return ya + (yb - ya) * t;
    }
    t = if t < 0.5 {
        0.5 * (2.0 * t).powf(1.0 + 10.0 * sharp)
    } else {
        1.0 - 0.5 * (2.0 * (1.0 - t)).powf(1.0 + 10.0 * sharp)
    };
    let (t2, t3) = (t * t, t * t * t);
    let h1 = 2.0 * t3 - 3.0 * t2 + 1.0;
    let h2 = -2.0 * t3 + 3.0 * t2;
    let h3 = t3 - 2.0 * t2 + t;
    let h4 = t3 - t2;
    let slope = (yb - ya) * (1.0 - sharp);
    let v = h1 * ya + h2 * yb + h3 * slope + h4 * slope;
    v.clamp(ya.min(yb), ya.max(yb))
}

/// Everything view-independent a renderer needs to shade: the transfer function and how the
/// mesh's scalar and lengths map onto it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Optics {
    pub tf: TransferFunction,
    /// The mesh scalar range mapped to s = 0 and s = 1.
    pub scalar_min: f64,
    pub scalar_max: f64,
    /// World length that κ is measured against (the bounding-box diagonal).
    pub length_unit: f64,
}

impl Optics {
    pub fn for_mesh(tf: TransferFunction, mesh: &datasets::TetMesh) -> Optics {
        Optics::for_extent(tf, &mesh.bounds(), mesh.scalar_range())
    }

    /// [`Optics::for_mesh`] from the mesh's bounds and scalar range alone (what a voxel data
    /// set knows without splitting its tets, `datasets::LazyDataset`).
    pub fn for_extent(tf: TransferFunction, bounds: &datasets::Aabb, range: (f32, f32)) -> Optics {
        Optics {
            tf,
            scalar_min: range.0 as f64,
            scalar_max: range.1 as f64,
            length_unit: bounds.diagonal(),
        }
    }

    /// Normalised scalar in [0, 1] (a constant field maps to 0).
    pub fn normalise(&self, s: f64) -> f64 {
        let d = self.scalar_max - self.scalar_min;
        if d > 0.0 {
            ((s - self.scalar_min) / d).clamp(0.0, 1.0)
        } else {
            0.0
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A fresh directory under the system temp dir (render-core has no tempfile dependency).
    fn scratch_dir(tag: &str) -> std::path::PathBuf {
        let d =
            std::env::temp_dir().join(format!("tetbench-transfer-{tag}-{}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    #[test]
    fn presets_are_valid_and_default_is_low_opacity() {
        for name in PRESET_NAMES {
            let tf = TransferFunction::preset(name).unwrap();
            tf.validate().unwrap();
            assert_eq!(tf.name, name);
        }
        assert_eq!(PRESET_NAMES[0], "low-opacity");
        let lo = TransferFunction::preset("low-opacity").unwrap();
        let hi = TransferFunction::preset("high-opacity").unwrap();
        assert!(hi.max_kappa() > 5.0 * lo.max_kappa());
        assert!(TransferFunction::preset("nope").is_none());
    }

    #[test]
    fn validation_rejects_bad_functions() {
        let mut tf = TransferFunction::preset("low-opacity").unwrap();
        tf.kappa[1].kappa = -1.0;
        assert!(matches!(
            tf.validate(),
            Err(TransferError::NegativeKappa { index: 1, .. })
        ));
        let mut tf = TransferFunction::preset("low-opacity").unwrap();
        tf.color.swap(0, 2);
        assert!(matches!(tf.validate(), Err(TransferError::Unsorted { .. })));
        let mut tf = TransferFunction::preset("low-opacity").unwrap();
        tf.kappa.clear();
        assert!(matches!(tf.validate(), Err(TransferError::Empty { .. })));
        let mut tf = TransferFunction::preset("low-opacity").unwrap();
        tf.color[0].rgb[1] = f64::NAN;
        assert!(matches!(
            tf.validate(),
            Err(TransferError::NonFinite { .. })
        ));
    }

    #[test]
    fn paraview_preset_is_read_rescaled_and_mapped() {
        let dir = scratch_dir("pv");
        let path = dir.join("cw.json");
        std::fs::write(
            &path,
            r#"[{"ColorSpace":"Diverging","Name":"Cool to Warm","RGBPoints":[-2,0.23,0.299,0.754, 0,0.865,0.865,0.865, 2,0.706,0.016,0.15],
                "Points":[-2,0,0.5,0, 2,0.5,0.5,0]}]"#,
        )
        .unwrap();
        let tf = TransferFunction::load(path.to_str().unwrap()).unwrap();
        assert_eq!(tf.name, "Cool to Warm");
        assert_eq!(tf.color.len(), 3);
        assert!((tf.color[1].s - 0.5).abs() < 1e-15 && (tf.color[2].s - 1.0).abs() < 1e-15);
        // o = 0.5 at the top: κ = 0.5 · K, as VTK's attenuation o / unit distance.
        assert!((tf.kappa_at(1.0) - 0.5 * PARAVIEW_OPACITY_SCALE).abs() < 1e-12);
        assert!((tf.kappa_at(0.5) - 0.25 * PARAVIEW_OPACITY_SCALE).abs() < 1e-12);
        assert_eq!(tf.kappa_at(0.0), 0.0);
        // A non-linear interval becomes 16 linear pieces that pass through the end values.
        std::fs::write(
            &path,
            r#"{"RGBPoints":[0,1,1,1, 1,1,1,1], "Points":[0,0,0.3,0.5, 1,0.9,0.5,0]}"#,
        )
        .unwrap();
        let tf = TransferFunction::from_paraview_json(&path).unwrap();
        assert_eq!(tf.kappa.len(), 17);
        assert!((tf.kappa_at(1.0) - 0.9 * PARAVIEW_OPACITY_SCALE).abs() < 1e-9);
        tf.validate().unwrap();
    }

    #[test]
    fn load_errors_name_the_file() {
        let dir = scratch_dir("err");
        let path = dir.join("broken.json");
        std::fs::write(&path, r#"{"RGBPoints":[0,1,1]}"#).unwrap();
        let err = TransferFunction::load(path.to_str().unwrap())
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("broken.json") && err.contains("multiple of 4"),
            "{err}"
        );
        std::fs::write(&path, "not json").unwrap();
        let err = TransferFunction::load(path.to_str().unwrap())
            .unwrap_err()
            .to_string();
        assert!(err.contains("broken.json") && err.contains("JSON"), "{err}");
        std::fs::write(&path, r#"{"RGBPoints":[1,1,1,1, 0,0,0,0]}"#).unwrap();
        let err = TransferFunction::load(path.to_str().unwrap())
            .unwrap_err()
            .to_string();
        assert!(err.contains("sorted"), "{err}");
        let err = TransferFunction::load("/no/such/tf.json")
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("/no/such/tf.json") && err.contains("low-opacity"),
            "{err}"
        );
        // A serialised transfer function round-trips.
        let tf = TransferFunction::preset("high-opacity").unwrap();
        std::fs::write(&path, serde_json::to_string(&tf).unwrap()).unwrap();
        assert_eq!(TransferFunction::load(path.to_str().unwrap()).unwrap(), tf);
    }
}
