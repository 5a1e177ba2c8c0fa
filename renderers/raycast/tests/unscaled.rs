//! The 2D table's `unscaled` perturbation (the positive control of our reading that the 2D
//! table keeps the 3D table's image, §2.2 and §4): without the scaling by the segment's length
//! that the paper's code applies, the image changes on a mesh whose segments vary in length,
//! and moves away from the 3D table's; the key is refused with the 3D table.

use raycast::{Mode, Raycast, RaycastSettings, TableKind, DESCRIPTION};
use render_core::image_error::psnr;
use render_core::{
    fixed_viewpoints, Camera, Gpu, Image, Optics, Projection, Renderer, TransferFunction,
};

fn image(table: TableKind, unscaled: bool) -> Image {
    let gpu = Gpu::new().expect("a wgpu adapter (install mesa-vulkan-drivers)");
    // A cubed-sphere shell: its radial and tangential edges differ, so the segments do.
    let mesh = std::sync::Arc::new(datasets::generate::from_spec("shell:20k", 1).unwrap());
    let optics = Optics::for_mesh(TransferFunction::preset("low-opacity").unwrap(), &mesh);
    let camera = Camera::fit(
        &mesh.bounds(),
        &fixed_viewpoints()[6],
        Projection::default(),
        48,
        48,
    );
    let mut r = Raycast::new(RaycastSettings {
        tiles: 2,
        table,
        mode: Mode::Loop,
        early_termination: false,
        unscaled,
        ..RaycastSettings::default()
    });
    r.prepare(&gpu, &mesh, &optics).unwrap();
    r.render(&gpu, &camera).unwrap();
    r.read_image(&gpu).unwrap()
}

/// Covered pixels whose channels differ by more than one 8-bit step (the image rules' count).
fn changed(a: &Image, b: &Image) -> u64 {
    render_core::image_error::compare(a, b).unwrap().bad_pixels
}

#[test]
fn the_unscaled_entry_changes_the_image_away_from_the_3d_tables() {
    let scaled = image(TableKind::TwoD, false);
    let unscaled = image(TableKind::TwoD, true);
    let exact = image(TableKind::ThreeD, false);
    assert!(scaled.pixels.iter().any(|p| p[3] > 0.05));
    let n = changed(&scaled, &unscaled);
    assert!(n > 0, "the unscaled 2D table drew the scaled one's image");
    // The scaling is the correction: without it the image is further from the 3D table's.
    let (with, without) = (psnr(&scaled, &exact), psnr(&unscaled, &exact));
    assert!(
        without < with,
        "against the 3D table: scaled {with:.1} dB, unscaled {without:.1} dB"
    );
}

#[test]
fn unscaled_is_written_only_where_set_and_only_with_the_2d_table() {
    let parse = |text: &str| {
        DESCRIPTION
            .parse_settings(text)
            .map_err(|e| anyhow::anyhow!("{e}"))
            .and_then(|s| RaycastSettings::from_settings(&s))
    };
    let base = "tiles=5x5;mode=passes;et=on;layers=8;k=8";
    let control = parse(&format!("{base};table=2d;unscaled=1")).unwrap();
    assert!(control.unscaled);
    assert!(!parse(&format!("{base};table=2d")).unwrap().unscaled);
    let e = parse(&format!("{base};table=3d;unscaled=1"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("unscaled") && e.contains("table=3d"), "{e}");
    let e = parse(&format!("{base};table=2d;unscaled=2"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("unscaled=2"), "{e}");
    assert_eq!(
        control.to_settings().to_string(),
        "tiles=5x5;table=2d;mode=passes;et=on;layers=8;k=8;unscaled=1"
    );
    for s in (DESCRIPTION.default_grid)() {
        assert!(s.get("unscaled").is_none(), "{s}");
    }
}
