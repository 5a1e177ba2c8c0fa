//! Voxel data sets without tets: the splatter draws a generated volume from
//! its grid alone — the same voxels, counters and image as from the volume's split mesh — and
//! nothing splits the volume into tets on the way.

use datasets::registry::Registry;
use datasets::LoadOptions;
use render_core::{Camera, Gpu, Optics, Projection, Renderer, TransferFunction, Viewpoint};
use splat::{Buckets, GpuSort, Splat, SplatSettings};

fn gpu() -> Gpu {
    Gpu::new().expect("a wgpu adapter (lavapipe: apt-get install mesa-vulkan-drivers)")
}

#[test]
fn a_voxel_only_data_set_renders_bit_for_bit_as_its_split_mesh() {
    let gpu = gpu();
    let registry = Registry::new(None);
    let options = LoadOptions::default();
    // 5 tets per support cell (`vol:`), 6 per cell of the whole grid (`fuel`); each under a
    // transfer function with κ(0) > 0 (the support's empty corners count) and one without.
    for (spec, tf) in [
        ("vol:20x18x16:eff=900", "low-opacity"),
        ("vol:20x18x16:eff=900", "zero-floor"),
        ("fuel", "low-opacity"),
    ] {
        let lazy = registry.resolve_lazy(spec, &options).unwrap();
        let volume = lazy.voxels().expect("a generated volume stays voxels");
        let eager = registry.resolve(spec, &options).unwrap();
        let mesh = &std::sync::Arc::new(eager.mesh);
        assert_eq!(lazy.num_tets(), mesh.num_tets(), "{spec}");
        assert_eq!(lazy.bounds(), mesh.bounds(), "{spec}");
        let tf = TransferFunction::preset(tf).unwrap();
        let optics = Optics::for_extent(tf.clone(), &lazy.bounds(), lazy.scalar_range());
        assert_eq!(optics, Optics::for_mesh(tf, mesh), "{spec}");
        let vp = Viewpoint::new("+x+y+z", [1.0, 1.0, 1.0]);
        let camera = Camera::fit(&lazy.bounds(), &vp, Projection::default(), 64, 48);
        for (buckets, sort) in [
            (Buckets::Gpu, GpuSort::Bitonic),
            (Buckets::Cpu, GpuSort::Radix),
        ] {
            let what = format!("{spec} {buckets:?} {sort:?}");
            let settings = SplatSettings {
                buckets,
                sort,
                ..Default::default()
            };
            let mut from_mesh = Splat::new(settings.clone());
            let prepared_mesh = from_mesh.prepare(&gpu, mesh, &optics).unwrap();
            let frame_mesh = from_mesh.render(&gpu, &camera).unwrap();
            let image_mesh = from_mesh.read_image(&gpu).unwrap();

            let mut from_voxels = Splat::new(settings);
            assert!(from_voxels.draws_voxels());
            let prepared = from_voxels.prepare_voxels(&gpu, volume, &optics).unwrap();
            let frame = from_voxels.render(&gpu, &camera).unwrap();
            let image = from_voxels.read_image(&gpu).unwrap();

            assert_eq!(prepared, prepared_mesh, "{what}");
            // Every counter but the rates (time-derived).
            let counts = |f: &render_core::FrameStats| {
                let mut c = f.counters.clone();
                c.retain(|(name, _)| !name.ends_with("_per_sec"));
                c
            };
            assert_eq!(counts(&frame), counts(&frame_mesh), "{what}");
            assert!(
                image.pixels.iter().any(|p| p[3] > 0.0),
                "{what}: empty image"
            );
            assert!(image == image_mesh, "{what}: the images differ");
        }
        assert!(!lazy.tets_built(), "{spec}: the splatter split the volume");
    }
}
