//! The messages of protocol version 1 (`docs/external-renderers.md`), built and read by pure
//! functions so the tests check them without a process.

use std::path::Path;

use datasets::TetMesh;
use render_core::{Camera, DeclaredAccuracy, FrameStats, Optics, Projection};

use crate::conformance::{LOWEST_DECLARED_DB, PASS_DB};
use serde_json::{json, Map, Value};

/// The protocol version tetbench speaks.
pub const PROTOCOL_VERSION: u64 = 1;

/// Entries of the sampled transfer function table in `prepare`.
pub const TABLE_ENTRIES: usize = 256;

/// Mesh files a renderer can ask for in its hello.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MeshFormat {
    Vtu,
    Raw,
}

/// What a renderer said about itself in its hello reply.
#[derive(Debug, Clone, PartialEq)]
pub struct Hello {
    pub name: String,
    pub version: String,
    /// Every setting as the renderer reported it (values as text).
    pub settings: Vec<(String, String)>,
    pub perspective: bool,
    pub orthographic: bool,
    pub formats: Vec<MeshFormat>,
    /// The accuracy it declares when it approximates by design (`accuracy` in the hello).
    pub accuracy: Option<DeclaredAccuracy>,
}

/// The `hello` request.
pub fn hello_request(settings: &[(String, String)]) -> Value {
    let map: Map<String, Value> = settings
        .iter()
        .map(|(k, v)| (k.clone(), Value::String(v.clone())))
        .collect();
    json!({"type": "hello", "protocol": PROTOCOL_VERSION, "settings": map})
}

/// A JSON scalar as the text a setting compares by (`0.5`, `"linear"` → `linear`).
fn as_text(v: &Value) -> String {
    match v {
        Value::String(s) => s.clone(),
        other => other.to_string(),
    }
}

/// Reads and checks a hello reply: protocol 1, every given setting confirmed with its value.
pub fn parse_hello(
    label: &str,
    reply: &Value,
    given: &[(String, String)],
) -> anyhow::Result<Hello> {
    match reply["protocol"].as_u64() {
        Some(PROTOCOL_VERSION) => {}
        Some(v) => anyhow::bail!(
            "{label} speaks protocol version {v}; tetbench speaks {PROTOCOL_VERSION} \
             (docs/external-renderers.md)"
        ),
        None => anyhow::bail!("{label}'s hello has no protocol version (expected \"protocol\": 1)"),
    }
    let settings: Vec<(String, String)> = reply["settings"]
        .as_object()
        .map(|m| m.iter().map(|(k, v)| (k.clone(), as_text(v))).collect())
        .unwrap_or_default();
    for (k, v) in given {
        match settings.iter().find(|(rk, _)| rk == k) {
            Some((_, rv)) if rv == v => {}
            Some((_, rv)) => anyhow::bail!(
                "{label} was given the setting {k}={v} but reports {k}={rv} in its hello"
            ),
            None => anyhow::bail!(
                "{label} was given the setting {k}={v} but its hello does not confirm it \
                 (a renderer must repeat every setting it uses, and answer an error for one it \
                 does not know)"
            ),
        }
    }
    let caps = &reply["capabilities"];
    let strings = |key: &str| -> Option<Vec<String>> {
        caps[key].as_array().map(|a| {
            a.iter()
                .filter_map(Value::as_str)
                .map(str::to_string)
                .collect()
        })
    };
    let projections =
        strings("projections").unwrap_or_else(|| vec!["perspective".into(), "orthographic".into()]);
    let mut formats = vec![];
    for f in strings("mesh_formats").unwrap_or_else(|| vec!["vtu".into()]) {
        formats.push(match f.as_str() {
            "vtu" => MeshFormat::Vtu,
            "raw" => MeshFormat::Raw,
            other => anyhow::bail!(
                "{label} asks for the mesh format {other:?}; tetbench writes \"vtu\" and \"raw\""
            ),
        });
    }
    if formats.is_empty() {
        anyhow::bail!("{label}'s hello lists no mesh format (\"vtu\" or \"raw\")");
    }
    let accuracy = parse_accuracy(label, &reply["accuracy"])?;
    Ok(Hello {
        name: reply["name"].as_str().unwrap_or(label).to_string(),
        version: reply["version"]
            .as_str()
            .map_or_else(|| reply["version"].to_string(), str::to_string),
        settings,
        perspective: projections.iter().any(|p| p == "perspective"),
        orthographic: projections.iter().any(|p| p == "orthographic"),
        formats,
        accuracy,
    })
}

/// The optional `accuracy` of a hello: `{"min_psnr_db": 20…35, "reason": "…"}`. Below
/// [`LOWEST_DECLARED_DB`] the check could no longer tell a renderer's approximation from a
/// convention mistake, so such a declaration is refused.
fn parse_accuracy(label: &str, v: &Value) -> anyhow::Result<Option<DeclaredAccuracy>> {
    if v.is_null() {
        return Ok(None);
    }
    let db = v["min_psnr_db"].as_f64();
    let reason = v["reason"].as_str().map(str::trim).unwrap_or("");
    match db {
        Some(db) if (LOWEST_DECLARED_DB..=PASS_DB).contains(&db) && !reason.is_empty() => {
            Ok(Some(DeclaredAccuracy {
                min_psnr_db: db,
                reason: reason.to_string(),
            }))
        }
        _ => anyhow::bail!(
            "{label}'s hello declares the accuracy {v}; expected {{\"min_psnr_db\": a number \
             from {LOWEST_DECLARED_DB} to {PASS_DB}, \"reason\": \"why, in words\"}} (below \
             {LOWEST_DECLARED_DB} dB no convention mistake could be told from the approximation)"
        ),
    }
}

/// Writes the mesh in the asked-for formats into `dir`; returns the `mesh` object of
/// `prepare`.
pub fn write_mesh(mesh: &TetMesh, formats: &[MeshFormat], dir: &Path) -> anyhow::Result<Value> {
    let b = mesh.bounds();
    let mut m = json!({
        "name": mesh.name,
        "points": mesh.num_points(),
        "tets": mesh.num_tets(),
        "scalar": mesh.scalar_name,
        "bounds": {"min": b.min, "max": b.max},
    });
    if formats.contains(&MeshFormat::Vtu) {
        let vtu = dir.join("mesh.vtu");
        datasets::write_vtu::write_vtu(mesh, &vtu).map_err(|e| anyhow::anyhow!("{e}"))?;
        m["vtu"] = json!(vtu);
    }
    if formats.contains(&MeshFormat::Raw) {
        let write = |name: &str, bytes: Vec<u8>| -> anyhow::Result<Value> {
            let path = dir.join(name);
            std::fs::write(&path, bytes)
                .map_err(|e| anyhow::anyhow!("cannot write {}: {e}", path.display()))?;
            Ok(json!(path))
        };
        let points: Vec<u8> = mesh
            .points
            .iter()
            .flatten()
            .flat_map(|v| v.to_le_bytes())
            .collect();
        let tets: Vec<u8> = mesh
            .tets
            .iter()
            .flatten()
            .flat_map(|v| v.to_le_bytes())
            .collect();
        let scalars: Vec<u8> = mesh.scalars.iter().flat_map(|v| v.to_le_bytes()).collect();
        m["raw"] = json!({
            "points": write("points.f32", points)?,
            "tets": write("tets.u32", tets)?,
            "scalars": write("scalars.f32", scalars)?,
        });
    }
    Ok(m)
}

/// Every control point of c or κ inside [0, 1], with 0 and 1, sorted: `[s, r, g, b, κ]`.
/// Between consecutive points both functions are linear.
pub fn shared_points(optics: &Optics) -> Vec<[f64; 5]> {
    let tf = &optics.tf;
    let mut s_points = tf.breakpoints();
    s_points.retain(|s| (0.0..=1.0).contains(s));
    for end in [0.0, 1.0] {
        if !s_points.contains(&end) {
            s_points.push(end);
        }
    }
    s_points.sort_by(f64::total_cmp);
    s_points
        .iter()
        .map(|&s| {
            let c = tf.color_at(s);
            [s, c[0], c[1], c[2], tf.kappa_at(s)]
        })
        .collect()
}

/// The `optics` object of `prepare`.
pub fn optics_json(optics: &Optics) -> Value {
    let tf = &optics.tf;
    json!({
        "model": "emission-absorption",
        "scalar_min": optics.scalar_min,
        "scalar_max": optics.scalar_max,
        "length_unit": optics.length_unit,
        "color": tf.color.iter().map(|p| [p.s, p.rgb[0], p.rgb[1], p.rgb[2]]).collect::<Vec<_>>(),
        "kappa": tf.kappa.iter().map(|p| [p.s, p.kappa]).collect::<Vec<_>>(),
        "points": shared_points(optics),
        "table": {"entries": TABLE_ENTRIES, "rgb_kappa": tf.rgb_kappa_table(TABLE_ENTRIES)},
    })
}

/// The `camera` object of `render`.
pub fn camera_json(camera: &Camera) -> Value {
    let vp = camera.view_proj();
    // glam stores columns; the protocol sends rows.
    let rows: Vec<[f64; 4]> = (0..4).map(|r| vp.row(r).to_array()).collect();
    let (projection, fovy, half) = match camera.projection {
        Projection::Perspective { fovy_deg } => ("perspective", Some(fovy_deg), None),
        Projection::Orthographic => ("orthographic", None, Some(camera.ortho_half_height)),
    };
    json!({
        "projection": projection,
        "eye": camera.eye,
        "target": camera.target,
        "up": camera.up,
        "fovy_deg": fovy,
        "ortho_half_height": half,
        "near": camera.near,
        "far": camera.far,
        "width": camera.width,
        "height": camera.height,
        "viewpoint": camera.viewpoint,
        "view_proj": rows,
    })
}

/// Turns a `rendered` reply and the exchange's own time into the frame's statistics
/// (protocol: the exchange is the frame's total, the renderer's wall time a stage).
pub fn frame_stats(label: &str, reply: &Value, exchange_ms: f64) -> anyhow::Result<FrameStats> {
    let number = |key: &str| -> anyhow::Result<Option<f64>> {
        match &reply[key] {
            Value::Null => Ok(None),
            v => match v.as_f64() {
                Some(x) if x.is_finite() && x >= 0.0 => Ok(Some(x)),
                _ => anyhow::bail!("{label} reported {key} = {v}, not a finite number ≥ 0"),
            },
        }
    };
    let wall = number("wall_ms")?
        .ok_or_else(|| anyhow::anyhow!("{label}'s `rendered` reply has no wall_ms"))?;
    let named = |key: &str| -> anyhow::Result<Vec<(String, f64)>> {
        let Some(m) = reply[key].as_object() else {
            return Ok(vec![]);
        };
        m.iter()
            .map(|(k, v)| match v.as_f64() {
                Some(x) if x.is_finite() => Ok((k.clone(), x)),
                _ => anyhow::bail!("{label} reported {key}.{k} = {v}, not a finite number"),
            })
            .collect()
    };
    let mut stages = vec![("renderer_wall_ms".to_string(), wall)];
    let reported_cpu = number("cpu_ms")?;
    if let Some(c) = reported_cpu {
        // Kept as reported, so the conformance check can hold it against the wall time.
        stages.push(("renderer_cpu_ms".to_string(), c));
    }
    stages.extend(named("stages")?);
    let overhead = (exchange_ms - wall).max(0.0);
    let cpu_ms = match reported_cpu {
        Some(c) => (c + overhead).min(exchange_ms),
        None => exchange_ms,
    };
    Ok(FrameStats {
        cpu_ms,
        gpu_ms: number("gpu_ms")?,
        total_ms: exchange_ms,
        frame_bytes: number("frame_bytes")?.unwrap_or(0.0) as u64,
        stages,
        counters: named("counters")?,
    })
}

/// Reads the image file a renderer wrote: width × height × RGBA f32 little-endian, row 0 at
/// the top.
pub fn read_image_file(
    label: &str,
    path: &Path,
    width: u32,
    height: u32,
) -> anyhow::Result<render_core::Image> {
    let bytes = std::fs::read(path)
        .map_err(|e| anyhow::anyhow!("{label} did not write its image {}: {e}", path.display()))?;
    let n = width as usize * height as usize;
    if bytes.len() != n * 16 {
        anyhow::bail!(
            "{label}'s image {} has {} bytes; a {width}×{height} image of RGBA f32 has {}",
            path.display(),
            bytes.len(),
            n * 16
        );
    }
    let pixels: Vec<[f32; 4]> = bytes
        .chunks_exact(16)
        .map(|p| {
            let f = |i: usize| f32::from_le_bytes([p[i], p[i + 1], p[i + 2], p[i + 3]]);
            [f(0), f(4), f(8), f(12)]
        })
        .collect();
    if let Some(i) = pixels.iter().position(|p| p.iter().any(|v| !v.is_finite())) {
        anyhow::bail!(
            "{label}'s image has a non-finite value at pixel ({}, {}): {:?}",
            i % width as usize,
            i / width as usize,
            pixels[i]
        );
    }
    Ok(render_core::Image {
        width,
        height,
        pixels,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use render_core::transfer::{ColorPoint, KappaPoint};
    use render_core::TransferFunction;

    fn optics(tf: TransferFunction) -> Optics {
        Optics {
            tf,
            scalar_min: -2.0,
            scalar_max: 6.0,
            length_unit: 10.0,
        }
    }

    /// Linear interpolation between the shared points gives back c(s) and κ(s) everywhere.
    #[test]
    fn shared_points_reproduce_both_functions() {
        let tf = TransferFunction {
            name: "t".into(),
            color: vec![
                ColorPoint {
                    s: 0.0,
                    rgb: [1.0, 0.0, 0.0],
                },
                ColorPoint {
                    s: 0.3,
                    rgb: [0.0, 1.0, 0.0],
                },
                ColorPoint {
                    s: 1.0,
                    rgb: [0.0, 0.0, 1.0],
                },
            ],
            kappa: vec![
                KappaPoint { s: 0.1, kappa: 2.0 },
                KappaPoint { s: 0.8, kappa: 8.0 },
            ],
        };
        let points = shared_points(&optics(tf.clone()));
        let s: Vec<f64> = points.iter().map(|p| p[0]).collect();
        assert_eq!(s, [0.0, 0.1, 0.3, 0.8, 1.0]);
        for i in 0..=200 {
            let x = i as f64 / 200.0;
            let j = points
                .partition_point(|p| p[0] <= x)
                .clamp(1, points.len() - 1);
            let (a, b) = (points[j - 1], points[j]);
            let t = ((x - a[0]) / (b[0] - a[0])).clamp(0.0, 1.0);
            let lerp = |k: usize| a[k] + t * (b[k] - a[k]);
            assert!((lerp(4) - tf.kappa_at(x)).abs() < 1e-12, "s={x}");
            for (k, c) in tf.color_at(x).iter().enumerate() {
                assert!((lerp(k + 1) - c).abs() < 1e-12, "s={x}");
            }
        }
    }

    #[test]
    fn hello_must_confirm_protocol_and_settings() {
        let given = vec![("step".to_string(), "0.5".to_string())];
        let ok = json!({"type": "hello", "protocol": 1, "name": "x", "settings": {"step": 0.5, "grid": 8},
                        "capabilities": {"mesh_formats": ["raw"], "projections": ["perspective"]}});
        let h = parse_hello("mine", &ok, &given).unwrap();
        assert_eq!(h.formats, [MeshFormat::Raw]);
        assert!(h.perspective && !h.orthographic);
        assert!(h.settings.contains(&("grid".into(), "8".into())));
        let v2 = json!({"type": "hello", "protocol": 2, "settings": {"step": "0.5"}});
        let e = parse_hello("mine", &v2, &given).unwrap_err().to_string();
        assert!(e.contains("protocol version 2"), "{e}");
        let other = json!({"type": "hello", "protocol": 1, "settings": {"step": "1"}});
        let e = parse_hello("mine", &other, &given).unwrap_err().to_string();
        assert!(e.contains("reports step=1"), "{e}");
        let silent = json!({"type": "hello", "protocol": 1});
        let e = parse_hello("mine", &silent, &given)
            .unwrap_err()
            .to_string();
        assert!(e.contains("does not confirm"), "{e}");
        // Defaults: both projections, .vtu.
        let h = parse_hello("mine", &silent, &[]).unwrap();
        assert_eq!(h.formats, [MeshFormat::Vtu]);
        assert!(h.perspective && h.orthographic);
        assert_eq!(h.accuracy, None);
    }

    /// A declared accuracy is read when it is a PSNR the check can still judge conventions
    /// at, with a reason; outside 20–35 dB or without a reason the hello is refused.
    #[test]
    fn declared_accuracy_is_read_and_bounded() {
        let hello = |acc: Value| json!({"type": "hello", "protocol": 1, "accuracy": acc});
        let h = parse_hello(
            "z",
            &hello(json!({"min_psnr_db": 25, "reason": "vertices snapped to pixels"})),
            &[],
        )
        .unwrap();
        let acc = h.accuracy.unwrap();
        assert_eq!(acc.min_psnr_db, 25.0);
        assert_eq!(acc.reason, "vertices snapped to pixels");
        for bad in [
            json!({"min_psnr_db": 12, "reason": "coarse"}),
            json!({"min_psnr_db": 40, "reason": "why"}),
            json!({"min_psnr_db": 25}),
            json!({"min_psnr_db": "25", "reason": "text"}),
            json!(25),
        ] {
            let e = parse_hello("z", &hello(bad.clone()), &[])
                .unwrap_err()
                .to_string();
            assert!(e.contains("declares the accuracy"), "{bad}: {e}");
        }
    }

    #[test]
    fn frame_time_is_the_exchange_and_the_renderer_wall_a_stage() {
        let r = json!({"type": "rendered", "wall_ms": 8.0, "cpu_ms": 2.0, "counters": {"n": 3}});
        let f = frame_stats("mine", &r, 10.0).unwrap();
        assert_eq!(f.total_ms, 10.0);
        assert_eq!(f.cpu_ms, 4.0); // 2 ms in the renderer + 2 ms of exchange overhead
        assert_eq!(f.stages[0], ("renderer_wall_ms".into(), 8.0));
        assert_eq!(f.stages[1], ("renderer_cpu_ms".into(), 2.0));
        assert_eq!(f.counters, [("n".to_string(), 3.0)]);
        let f = frame_stats("mine", &json!({"wall_ms": 8.0}), 10.0).unwrap();
        assert_eq!(f.cpu_ms, 10.0);
        assert!(frame_stats("mine", &json!({"cpu_ms": 1.0}), 10.0).is_err());
        assert!(frame_stats("mine", &json!({"wall_ms": -1.0}), 10.0).is_err());
    }

    #[test]
    fn camera_rows_project_the_target_to_the_centre() {
        let b = datasets::Aabb {
            min: [0.0; 3],
            max: [2.0, 1.0, 1.0],
        };
        let vp = render_core::fixed_viewpoints()[7].clone();
        let cam = Camera::fit(&b, &vp, Projection::default(), 64, 32);
        let j = camera_json(&cam);
        let m = j["view_proj"].as_array().unwrap();
        let t = [cam.target[0], cam.target[1], cam.target[2], 1.0];
        let row = |r: usize| -> f64 {
            (0..4)
                .map(|c| m[r][c].as_f64().unwrap() * t[c])
                .sum::<f64>()
        };
        let w = row(3);
        assert!(row(0).abs() / w < 1e-12 && row(1).abs() / w < 1e-12);
        assert_eq!(j["fovy_deg"], json!(30.0));
        assert!(j["ortho_half_height"].is_null());
    }
}
