//! The paper's knobs as typed settings, and the variants the harness runs.

use anyhow::anyhow;
use render_core::Settings;

/// Which pre-integration table composites a segment (§2.2, §4).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TableKind {
    /// (s_front, s_back) for one fixed length, scaled by the segment length as the paper's
    /// code does; every figure of the paper except Table 6.
    TwoD,
    /// (s_front, s_back, length / longest edge); the paper's Table 6.
    ThreeD,
}

impl TableKind {
    pub fn name(self) -> &'static str {
        match self {
            TableKind::TwoD => "2d",
            TableKind::ThreeD => "3d",
        }
    }
}

/// How ray steps are scheduled.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mode {
    /// Faithful: one GPU pass per ray step and tile, as on 2005 hardware; per peeling layer, a
    /// tile moves on to the next when a count of its active rays (every [`crate::COUNT_EVERY`]
    /// passes) is zero, and stops when no ray starts again.
    Passes,
    /// Modern: one compute dispatch per tile in which every ray loops until it is done.
    Loop,
}

impl Mode {
    pub fn name(self) -> &'static str {
        match self {
            Mode::Passes => "passes",
            Mode::Loop => "loop",
        }
    }
}

/// The settings of one variant.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RaycastSettings {
    /// N for an N×N tiling of the screen (§2.3; the paper: 1…6).
    pub tiles: u32,
    pub table: TableKind,
    pub mode: Mode,
    /// Early ray termination at opacity [`crate::ET_OPACITY`].
    pub early_termination: bool,
    /// Most peeling layers (§2.4); re-entries beyond are counted as dropped.
    pub max_layers: u32,
    /// mode=passes: a tile's active rays are counted after every `k` passes (§3.2 phase 3b,
    /// the paper's occlusion query; it does not give k). Default [`crate::COUNT_EVERY`].
    pub k: u32,
    /// A perturbation, not a configuration (the positive control of the 2D table's image
    /// claim): the 2D table's entry composited as it stands, without the scaling by the
    /// segment's length that the paper's code applies (§2.2), so every segment counts as one of
    /// the table's length. Only with [`TableKind::TwoD`].
    pub unscaled: bool,
}

impl Default for RaycastSettings {
    fn default() -> Self {
        RaycastSettings {
            tiles: 5,
            table: TableKind::TwoD,
            mode: Mode::Passes,
            early_termination: true,
            max_layers: 8,
            k: crate::COUNT_EVERY,
            unscaled: false,
        }
    }
}

impl RaycastSettings {
    pub fn to_settings(&self) -> Settings {
        let settings = Settings::new()
            .with("tiles", format!("{0}x{0}", self.tiles))
            .with("table", self.table.name())
            .with("mode", self.mode.name())
            .with("et", self.early_termination)
            .with("layers", self.max_layers)
            .with("k", self.k);
        // A perturbation is written only where set: every other variant keeps its settings.
        if self.unscaled {
            settings.with("unscaled", 1)
        } else {
            settings
        }
    }

    /// The typed settings of a variant, checked by [`RaycastSettings::validate`].
    pub fn from_settings(s: &Settings) -> anyhow::Result<RaycastSettings> {
        let tiles_text = s.require_text("tiles")?;
        let tiles = match tiles_text.split_once('x') {
            Some((a, b)) if a == b => a.parse().ok(),
            _ => None,
        }
        .ok_or_else(|| anyhow!("raycast: tiles={tiles_text} is not NxN (1x1 … 6x6)"))?;
        let table = match s.require_text("table")?.as_str() {
            "2d" => TableKind::TwoD,
            "3d" => TableKind::ThreeD,
            v => return Err(anyhow!("raycast: table={v} is neither 2d nor 3d")),
        };
        let mode = match s.require_text("mode")?.as_str() {
            "passes" => Mode::Passes,
            "loop" => Mode::Loop,
            v => return Err(anyhow!("raycast: mode={v} is neither passes nor loop")),
        };
        let layers = s.require_int("layers")?;
        // Rows written before k was a setting ran it at the default.
        let k = s.int("k").unwrap_or(crate::COUNT_EVERY as i64);
        let unscaled = match s.get("unscaled") {
            None => false,
            Some(_) => match s.require_int("unscaled")? {
                1 => true,
                v => return Err(anyhow!("raycast: unscaled={v} is not 1 (absent: scaled)")),
            },
        };
        let settings = RaycastSettings {
            tiles,
            table,
            mode,
            early_termination: s.require_switch("et")?,
            max_layers: u32::try_from(layers)
                .map_err(|_| anyhow!("raycast: layers={layers} is negative"))?,
            k: u32::try_from(k).map_err(|_| anyhow!("raycast: k={k} is negative"))?,
            unscaled,
        };
        settings.validate()?;
        Ok(settings)
    }

    /// Checks the ranges (tiles 1…6, 1 … 64 layers, k 1 … 64) and that `unscaled` perturbs
    /// the 2D table only.
    pub fn validate(&self) -> anyhow::Result<()> {
        if self.unscaled && self.table != TableKind::TwoD {
            return Err(anyhow!(
                "raycast: unscaled=1 perturbs the 2D table only, not table={}",
                self.table.name()
            ));
        }
        if !(1..=6).contains(&self.tiles) {
            return Err(anyhow!(
                "raycast: tiles must be 1x1 … 6x6, got {}",
                self.tiles
            ));
        }
        if self.max_layers == 0 || self.max_layers > 64 {
            return Err(anyhow!(
                "raycast: layers must be 1 … 64, got {}",
                self.max_layers
            ));
        }
        if !(1..=64).contains(&self.k) {
            return Err(anyhow!("raycast: k must be 1 … 64, got {}", self.k));
        }
        Ok(())
    }
}

/// Peeling-layer limits `--settings layers=…` can choose.
pub const LAYER_CHOICES: [u32; 4] = [4, 8, 16, 32];

/// The settings of the default variants (the default suite runs each, so they are kept to
/// two): the paper's configuration (5×5 tiles, 2D table, one pass per step, early termination)
/// and the exact-order image (3D table, no early termination) in the modern looping mode. Every
/// other combination is reachable with `--settings` (e.g.
/// `tiles=1x1|5x5;table=2d|3d;mode=passes|loop`).
pub fn default_settings() -> Vec<RaycastSettings> {
    let base = RaycastSettings::default();
    vec![
        base,
        RaycastSettings {
            table: TableKind::ThreeD,
            early_termination: false,
            mode: Mode::Loop,
            ..base
        },
    ]
}

/// Values of k the full grid offers in mode=passes: the default, and a count after every pass
/// (the rounding k adds, measured against it).
pub const K_CHOICES: [u32; 2] = [crate::COUNT_EVERY, 1];

/// Every combination: tiles 1…6 × table × mode × et × layers, and in mode=passes × k
/// ([`K_CHOICES`]; mode=loop issues no counts and keeps the default).
pub fn all_settings() -> Vec<RaycastSettings> {
    let mut v = Vec::new();
    for tiles in 1..=6 {
        for table in [TableKind::TwoD, TableKind::ThreeD] {
            for mode in [Mode::Passes, Mode::Loop] {
                let ks: &[u32] = match mode {
                    Mode::Passes => &K_CHOICES,
                    Mode::Loop => &K_CHOICES[..1],
                };
                for early_termination in [true, false] {
                    for max_layers in LAYER_CHOICES {
                        for &k in ks {
                            v.push(RaycastSettings {
                                tiles,
                                table,
                                mode,
                                early_termination,
                                max_layers,
                                k,
                                unscaled: false,
                            });
                        }
                    }
                }
            }
        }
    }
    // The positive control of the 2D table's image claim (R8): its variant (5×5 tiles, one pass
    // per step, early termination, 8 layers) with the entry unscaled.
    v.push(RaycastSettings {
        unscaled: true,
        ..RaycastSettings::default()
    });
    v
}
