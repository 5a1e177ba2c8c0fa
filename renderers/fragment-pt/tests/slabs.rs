//! The bucket sort's `slabs` perturbation (the positive control of the paper's claim that the
//! bucket sort's image is indistinguishable, §3.2 and §5): the paper's slabs are the default
//! image bit for bit, a tenth of them draws a visibly different image of a non-convex mesh, and
//! the key is refused where there is no bucket sort to perturb.

use fragment_pt::{FragmentPt, FragmentPtSettings, Shading, SortMode, DESCRIPTION};
use render_core::{Camera, Gpu, Image, Optics, Projection, Renderer, TransferFunction, Viewpoint};

fn image(slabs: Option<usize>) -> Image {
    let gpu = Gpu::new().expect("a wgpu adapter (install mesa-vulkan-drivers)");
    // A hollow sphere: rays cross its near and far walls, which few slabs put in one slab.
    let mesh = std::sync::Arc::new(datasets::generate::from_spec("shell:20k", 1).unwrap());
    let optics = Optics::for_mesh(TransferFunction::preset("high-opacity").unwrap(), &mesh);
    let vp = Viewpoint::new("oblique", [0.4, 0.6, 0.7]);
    let cam = Camera::fit(&mesh.bounds(), &vp, Projection::default(), 64, 64);
    let mut r = FragmentPt::new(FragmentPtSettings {
        shading: Shading::Average,
        sort: SortMode::Bucket,
        slabs,
    });
    r.prepare(&gpu, &mesh, &optics).unwrap();
    r.render(&gpu, &cam).unwrap();
    r.read_image(&gpu).unwrap()
}

/// Covered pixels whose channels differ by more than one 8-bit step (the image rules' count).
fn changed(a: &Image, b: &Image) -> u64 {
    render_core::image_error::compare(a, b).unwrap().bad_pixels
}

#[test]
fn fewer_slabs_change_the_image_and_the_papers_slabs_do_not() {
    let paper = image(None);
    assert!(paper.pixels.iter().any(|p| p[3] > 0.1));
    assert_eq!(paper.pixels, image(Some(20)).pixels);
    let coarse = image(Some(2));
    let n = changed(&paper, &coarse);
    assert!(n > 0, "2 slabs drew the 20-slab image");
}

#[test]
fn slabs_is_written_only_where_set_and_only_with_the_bucket_sort() {
    let parse = |text: &str| {
        DESCRIPTION
            .parse_settings(text)
            .map_err(|e| anyhow::anyhow!("{e}"))
            .and_then(|s| fragment_pt::from_settings(&s))
    };
    let control = parse("shading=average;sort=bucket;slabs=2").unwrap();
    assert_eq!(control.slabs, Some(2));
    assert_eq!(
        parse("shading=average;sort=bucket").unwrap().slabs,
        None,
        "the paper's bucket sort carries no slabs"
    );
    for bad in [
        "shading=average;sort=merge;slabs=2",
        "shading=psi;sort=gpu;slabs=20",
    ] {
        let e = parse(bad).unwrap_err().to_string();
        assert!(e.contains("slabs"), "{bad}: {e}");
    }
    let e = parse("shading=average;sort=bucket;slabs=0")
        .unwrap_err()
        .to_string();
    assert!(e.contains("slabs=0"), "{e}");
    // Built from its settings, the variant reports them back, the key only where set.
    let built = (DESCRIPTION.build)(
        &DESCRIPTION
            .parse_settings("shading=average;sort=bucket;slabs=2")
            .unwrap(),
    )
    .unwrap();
    assert_eq!(
        built.settings().to_string(),
        "shading=average;sort=bucket;slabs=2"
    );
    for s in (DESCRIPTION.default_grid)() {
        assert!(s.get("slabs").is_none(), "{s}");
    }
}
