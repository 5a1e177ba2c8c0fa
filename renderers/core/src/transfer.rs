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
        let t = if b.s > a.s { (s - a.s) / (b.s - a.s) } else { 0.0 };
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
        let t = if b.s > a.s { (s - a.s) / (b.s - a.s) } else { 0.0 };
        a.kappa + t * (b.kappa - a.kappa)
    }

    /// Every scalar value where c or κ has a kink, sorted and deduplicated: exact integration
    /// splits a segment there so that each piece is linear in s.
    pub fn breakpoints(&self) -> Vec<f64> {
        let mut b: Vec<f64> = self.color.iter().map(|p| p.s).chain(self.kappa.iter().map(|p| p.s)).collect();
        b.sort_by(|x, y| x.total_cmp(y));
        b.dedup();
        b
    }

    /// The largest κ anywhere (bounds opacity per unit length).
    pub fn max_kappa(&self) -> f64 {
        self.kappa.iter().map(|p| p.kappa).fold(0.0, f64::max)
    }
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
        let (lo, hi) = mesh.scalar_range();
        Optics { tf, scalar_min: lo as f64, scalar_max: hi as f64, length_unit: mesh.bounds().diagonal() }
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
