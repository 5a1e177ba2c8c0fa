//! CPU twin of the shaders' ray arithmetic, in f32 with the same formulas: the pixel ray, the
//! entry parameter of the first-hit and peeling shaders, one ray step (exit face, next tet,
//! exit λ and scalar — `exit_of` in common.wgsl) and a whole walk through the peeling layers
//! (the step count a pixel needs, what mode=passes spends passes on). Tests compare the GPU
//! with these.

use crate::layout::{MeshLayout, TetRef, NONE};

/// The pixel-ray parameters the shaders receive (object coordinates).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RayFrame {
    pub o0: [f32; 3],
    pub ox: [f32; 3],
    pub oy: [f32; 3],
    pub d0: [f32; 3],
    pub dx: [f32; 3],
    pub dy: [f32; 3],
    pub width: u32,
    pub height: u32,
}

impl RayFrame {
    /// Parameters for `camera` with the object origin at `origin` (world), computed in f64.
    pub fn new(camera: &render_core::Camera, origin: [f64; 3]) -> RayFrame {
        use glam::DVec3;
        let eye = DVec3::from(camera.eye) - DVec3::from(origin);
        let fwd = DVec3::from(camera.forward());
        let right = fwd.cross(DVec3::from(camera.up)).normalize();
        let up = right.cross(fwd);
        let aspect = camera.width as f64 / camera.height as f64;
        let f = |v: DVec3| [v.x as f32, v.y as f32, v.z as f32];
        let zero = [0.0f32; 3];
        match camera.projection {
            render_core::Projection::Perspective { fovy_deg } => {
                let t = (fovy_deg.to_radians() * 0.5).tan();
                RayFrame {
                    o0: f(eye),
                    ox: zero,
                    oy: zero,
                    d0: f(fwd),
                    dx: f(right * (t * aspect)),
                    dy: f(up * t),
                    width: camera.width,
                    height: camera.height,
                }
            }
            render_core::Projection::Orthographic => {
                let h = camera.ortho_half_height;
                RayFrame {
                    o0: f(eye),
                    ox: f(right * (h * aspect)),
                    oy: f(up * h),
                    d0: f(fwd),
                    dx: zero,
                    dy: zero,
                    width: camera.width,
                    height: camera.height,
                }
            }
        }
    }

    /// The ray through pixel centre (`px`, `py`) (`pixel_ray` in common.wgsl).
    pub fn ray(&self, px: f32, py: f32) -> ([f32; 3], [f32; 3]) {
        let nx = px / self.width as f32 * 2.0 - 1.0;
        let ny = 1.0 - py / self.height as f32 * 2.0;
        let o = std::array::from_fn(|a| self.o0[a] + nx * self.ox[a] + ny * self.oy[a]);
        let d: [f32; 3] = std::array::from_fn(|a| self.d0[a] + nx * self.dx[a] + ny * self.dy[a]);
        let l = dot(d, d).sqrt();
        (o, d.map(|v| v / l))
    }
}

fn dot(a: [f32; 3], b: [f32; 3]) -> f32 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn sub(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

/// Eq. 1's numerators and denominators for the four faces of `t`.
fn planes(layout: &MeshLayout, t: TetRef, o: [f32; 3], d: [f32; 3]) -> ([f32; 4], [f32; 4]) {
    let x = layout.texels(t);
    let v = |k: usize| x[k].map(f32::from_bits);
    let (v0, v1, v2, n0, n1, n2) = (v(0), v(1), v(2), v(3), v(4), v(5));
    let p3 = |a: [f32; 4]| [a[0], a[1], a[2]];
    let v3 = [v0[3], v1[3], v2[3]];
    let n3 = [n0[3], n1[3], n2[3]];
    let num = [
        dot(sub(v3, o), p3(n0)),
        dot(sub(p3(v2), o), p3(n1)),
        dot(sub(p3(v1), o), p3(n2)),
        dot(sub(p3(v0), o), n3),
    ];
    let den = [dot(d, p3(n0)), dot(d, p3(n1)), dot(d, p3(n2)), dot(d, n3)];
    (num, den)
}

/// s(x) = g·x + c of tet `t` (normalised scalar).
pub fn scalar_at(layout: &MeshLayout, t: TetRef, x: [f32; 3]) -> f32 {
    let g = layout.texels(t)[8].map(f32::from_bits);
    dot([g[0], g[1], g[2]], x) + g[3]
}

/// Entry parameter into `t`: the largest λ among faces with a negative denominator.
pub fn entry_lambda(layout: &MeshLayout, t: TetRef, o: [f32; 3], d: [f32; 3]) -> f32 {
    let (num, den) = planes(layout, t, o, d);
    let mut best = f32::NEG_INFINITY;
    for f in 0..4 {
        if den[f] < 0.0 {
            best = best.max(num[f] / den[f]);
        }
    }
    if best == f32::NEG_INFINITY {
        0.0
    } else {
        best
    }
}

/// One step of a ray through tet `t` entered at `lambda`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Exit {
    /// Exit face (0..4), or 4 when no face has a positive denominator.
    pub face: u32,
    pub next: TetRef,
    pub lambda: f32,
    pub s: f32,
    /// The two smallest candidate exit parameters (for judging ties in tests).
    pub runner_up: f32,
}

/// The exit of the ray from `t` (`exit_of` in common.wgsl).
pub fn exit_of(layout: &MeshLayout, t: TetRef, o: [f32; 3], d: [f32; 3], lambda: f32) -> Exit {
    let (num, den) = planes(layout, t, o, d);
    let mut best = f32::MAX;
    let mut runner_up = f32::MAX;
    let mut face = 4u32;
    for f in 0..4 {
        if den[f] > 0.0 {
            let l = num[f] / den[f];
            if l < best {
                runner_up = best;
                best = l;
                face = f as u32;
            } else if l < runner_up {
                runner_up = l;
            }
        }
    }
    let mut out = Exit {
        face,
        next: TetRef::NONE,
        lambda,
        s: 0.0,
        runner_up,
    };
    if face < 4 {
        out.lambda = best.max(lambda);
        let nb = layout.texels(t)[6 + face as usize / 2];
        let pair = if face & 1 == 0 {
            [nb[0], nb[1]]
        } else {
            [nb[2], nb[3]]
        };
        out.next = TetRef {
            chunk: pair[0],
            local: pair[1],
        };
    }
    let x = std::array::from_fn(|a| o[a] + out.lambda * d[a]);
    out.s = scalar_at(layout, t, x);
    out
}

/// A peeling-layer entry as the GPU stores it: (tet, λ, s).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LayerEntry {
    pub tet: TetRef,
    pub lambda: f32,
    pub s: f32,
}

impl LayerEntry {
    /// Decodes a texel of the layer texture (`None` where the layer is empty).
    pub fn decode(texel: [u32; 4]) -> Option<LayerEntry> {
        (texel[0] != NONE).then(|| LayerEntry {
            tet: TetRef {
                chunk: texel[0],
                local: texel[1],
            },
            lambda: f32::from_bits(texel[2]),
            s: f32::from_bits(texel[3]),
        })
    }
}

/// What a whole walk of one ray did.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Walk {
    pub steps: u32,
    pub skipped_entries: u32,
    pub stalled: bool,
}

/// Walks a ray through every peeling layer (no early termination), as cast.wgsl's `advance`
/// and `next_layer` do: one step per tet, a ray that leaves continues at the next layer entry
/// not behind it (by more than `bias`), at most `max_steps` steps.
pub fn walk(
    layout: &MeshLayout,
    layers: &[Option<LayerEntry>],
    o: [f32; 3],
    d: [f32; 3],
    bias: f32,
    max_steps: u32,
) -> Walk {
    walk_segments(layout, layers, o, d, bias, max_steps).0
}

/// [`walk`], and the steps of each stretch between an entry and the ray's exit from the mesh
/// (one per layer the ray walked from, in order): what mode=passes spends per layer.
pub fn walk_segments(
    layout: &MeshLayout,
    layers: &[Option<LayerEntry>],
    o: [f32; 3],
    d: [f32; 3],
    bias: f32,
    max_steps: u32,
) -> (Walk, Vec<u32>) {
    let mut w = Walk::default();
    let mut segments = Vec::new();
    let Some(Some(first)) = layers.first() else {
        return (w, segments);
    };
    let (mut tet, mut lambda) = (first.tet, first.lambda);
    let mut layer = 0usize;
    let mut segment = 0u32;
    loop {
        let ex = exit_of(layout, tet, o, d, lambda);
        w.steps += 1;
        segment += 1;
        tet = ex.next;
        lambda = ex.lambda;
        if w.steps >= max_steps {
            w.stalled = true;
            segments.push(segment);
            return (w, segments);
        }
        if tet.is_none() {
            segments.push(std::mem::take(&mut segment));
            loop {
                layer += 1;
                match layers.get(layer).copied().flatten() {
                    None => return (w, segments),
                    Some(e) if e.lambda >= lambda - bias => {
                        tet = e.tet;
                        lambda = e.lambda;
                        break;
                    }
                    Some(_) => w.skipped_entries += 1,
                }
            }
        }
    }
}
