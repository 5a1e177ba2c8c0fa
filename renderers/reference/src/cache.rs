//! The on-disk cache of reference images: one file per (reference code, mesh content, optics,
//! camera, size), checked by magic, key, size and a checksum of the pixels; anything that does
//! not match is re-rendered and replaced, never trusted.

use std::io::Write;
use std::path::{Path, PathBuf};

use datasets::TetMesh;
use render_core::{Camera, Image, Optics};

use crate::Prepared;

/// blake3 (hex) of the reference renderer's own code, computed by `build.rs` at build time: every
/// `src/**/*.rs` file of this crate, its version, and every file of render-core's
/// `preintegration/` (the segment integrator each step calls). Part of every cache key, so any
/// change to the code that makes the images invalidates the images cached before it.
pub const CODE_HASH: &str = env!("REFERENCE_CODE_HASH");

const CACHE_MAGIC: &[u8; 8] = b"TBREF\x00\x00\x02";
/// The file layout's version (the code itself is covered by [`CODE_HASH`]).
const CACHE_VERSION: u32 = 2;
/// Magic, key, width, height, lost rays.
const HEADER: usize = 8 + 32 + 4 + 4 + 8;

/// A reference image and what the walk could not follow.
#[derive(Debug, Clone, PartialEq)]
pub struct Reference {
    pub image: Image,
    /// Pixel rays whose walk ended early, not by leaving the mesh
    /// ([`crate::RenderStats::lost_rays`]).
    pub lost_rays: u64,
}

/// The cache key as a pure function of its inputs: blake3 of the JSON of the reference code's
/// hash, the layout version, the mesh's content hash, the optics, the camera and the size.
pub fn cache_key_for(
    code_hash: &str,
    mesh_hash: &str,
    optics: &Optics,
    camera: &Camera,
) -> [u8; 32] {
    let json = serde_json::json!({
        "code": code_hash,
        "version": CACHE_VERSION,
        "mesh": mesh_hash,
        "optics": optics,
        "camera": camera,
        "size": [camera.width, camera.height],
    });
    *blake3::hash(json.to_string().as_bytes()).as_bytes()
}

fn cache_key(mesh: &TetMesh, optics: &Optics, camera: &Camera) -> [u8; 32] {
    cache_key_for(CODE_HASH, mesh.content_hash(), optics, camera)
}

fn cache_path(dir: &Path, key: &[u8; 32]) -> PathBuf {
    let hex: String = key[..16].iter().map(|b| format!("{b:02x}")).collect();
    dir.join(format!("{hex}.tbref"))
}

/// Reads a cached reference; any mismatch (magic, key, size, length, checksum) gives `None`.
fn read_cache(path: &Path, key: &[u8; 32], w: u32, h: u32) -> Option<Reference> {
    let bytes = std::fs::read(path).ok()?;
    let n = (w as usize) * (h as usize) * 16;
    if bytes.len() != HEADER + n + 32 || &bytes[..8] != CACHE_MAGIC || &bytes[8..40] != key {
        return None;
    }
    let (fw, fh) = (
        u32::from_le_bytes(bytes[40..44].try_into().ok()?),
        u32::from_le_bytes(bytes[44..48].try_into().ok()?),
    );
    if (fw, fh) != (w, h) {
        return None;
    }
    // The checksum covers the counter and the pixels.
    let checked = &bytes[48..HEADER + n];
    if blake3::hash(checked).as_bytes() != &bytes[HEADER + n..] {
        return None;
    }
    let lost_rays = u64::from_le_bytes(bytes[48..56].try_into().ok()?);
    let pixels = bytes[HEADER..HEADER + n]
        .chunks_exact(16)
        .map(|c| {
            std::array::from_fn(|k| f32::from_le_bytes(c[4 * k..4 * k + 4].try_into().unwrap()))
        })
        .collect::<Vec<[f32; 4]>>();
    if pixels.iter().flatten().any(|v| !v.is_finite()) {
        return None;
    }
    Some(Reference {
        image: Image {
            width: w,
            height: h,
            pixels,
        },
        lost_rays,
    })
}

fn write_cache(path: &Path, key: &[u8; 32], r: &Reference) -> anyhow::Result<()> {
    let dir = path.parent().unwrap_or(Path::new("."));
    std::fs::create_dir_all(dir).map_err(|e| {
        anyhow::anyhow!(
            "cannot create reference cache directory {}: {e}",
            dir.display()
        )
    })?;
    let img = &r.image;
    let mut checked = Vec::with_capacity(8 + img.pixels.len() * 16);
    checked.extend_from_slice(&r.lost_rays.to_le_bytes());
    for p in &img.pixels {
        for v in p {
            checked.extend_from_slice(&v.to_le_bytes());
        }
    }
    // A temporary file beside it, renamed over it (tempfile's persist): a reader sees the old
    // file or the whole new one; the temporary file is removed if anything fails.
    let write = || -> std::io::Result<()> {
        let mut tmp = tempfile::Builder::new()
            .prefix(".reference-")
            .suffix(".tmp")
            .tempfile_in(dir)?;
        let f = tmp.as_file_mut();
        f.write_all(CACHE_MAGIC)?;
        f.write_all(key)?;
        f.write_all(&img.width.to_le_bytes())?;
        f.write_all(&img.height.to_le_bytes())?;
        f.write_all(&checked)?;
        f.write_all(blake3::hash(&checked).as_bytes())?;
        f.sync_all()?;
        tmp.persist(path).map(|_| ()).map_err(|e| e.error)
    };
    write()
        .map_err(|e| anyhow::anyhow!("cannot write reference cache file {}: {e}", path.display()))
}

/// The reference image, from `cache_dir` when a valid file for exactly this reference code,
/// mesh (content hash), camera, optics and size exists; otherwise rendered and stored. Damaged
/// or mismatched files are re-rendered and replaced, never trusted.
pub fn render_cached(
    mesh: &TetMesh,
    optics: &Optics,
    camera: &Camera,
    cache_dir: &Path,
) -> anyhow::Result<Image> {
    Ok(render_cached_reference(mesh, optics, camera, cache_dir)?.image)
}

/// [`render_cached`] with the count of lost rays.
pub fn render_cached_reference(
    mesh: &TetMesh,
    optics: &Optics,
    camera: &Camera,
    cache_dir: &Path,
) -> anyhow::Result<Reference> {
    if let Some(r) = read_cached_reference(mesh, optics, camera, cache_dir) {
        return Ok(r);
    }
    Prepared::new(mesh).render_cached_reference(optics, camera, cache_dir)
}

/// The cached reference image for these inputs, if a valid one exists (nothing is rendered).
pub fn read_cached(
    mesh: &TetMesh,
    optics: &Optics,
    camera: &Camera,
    cache_dir: &Path,
) -> Option<Image> {
    read_cached_reference(mesh, optics, camera, cache_dir).map(|r| r.image)
}

/// [`read_cached`] with the count of lost rays.
pub fn read_cached_reference(
    mesh: &TetMesh,
    optics: &Optics,
    camera: &Camera,
    cache_dir: &Path,
) -> Option<Reference> {
    let key = cache_key(mesh, optics, camera);
    read_cache(
        &cache_path(cache_dir, &key),
        &key,
        camera.width,
        camera.height,
    )
}

/// Where [`render_cached`] keeps the image for these inputs.
pub fn cache_file(mesh: &TetMesh, optics: &Optics, camera: &Camera, cache_dir: &Path) -> PathBuf {
    cache_path(cache_dir, &cache_key(mesh, optics, camera))
}

impl Prepared<'_> {
    /// [`render_cached`] with this prepared mesh.
    pub fn render_cached(
        &self,
        optics: &Optics,
        camera: &Camera,
        cache_dir: &Path,
    ) -> anyhow::Result<Image> {
        Ok(self
            .render_cached_reference(optics, camera, cache_dir)?
            .image)
    }

    /// [`render_cached_reference`] with this prepared mesh.
    pub fn render_cached_reference(
        &self,
        optics: &Optics,
        camera: &Camera,
        cache_dir: &Path,
    ) -> anyhow::Result<Reference> {
        let key = cache_key(self.mesh(), optics, camera);
        let path = cache_path(cache_dir, &key);
        if let Some(r) = read_cache(&path, &key, camera.width, camera.height) {
            return Ok(r);
        }
        let (image, stats) = self.render(optics, camera);
        let r = Reference {
            image,
            lost_rays: stats.lost_rays,
        };
        write_cache(&path, &key, &r)?;
        Ok(r)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use render_core::{fixed_viewpoints, Projection, TransferFunction};

    #[test]
    fn code_hash_is_a_blake3_hex_digest() {
        assert_eq!(CODE_HASH.len(), 64);
        assert!(CODE_HASH.bytes().all(|c| c.is_ascii_hexdigit()));
    }

    #[test]
    fn key_changes_with_the_code_hash_and_only_with_its_inputs() {
        let mesh = datasets::generate::from_spec("box:1k", 1).unwrap();
        let optics = Optics::for_mesh(TransferFunction::preset("low-opacity").unwrap(), &mesh);
        let vp = &fixed_viewpoints()[0];
        let cam = Camera::fit(&mesh.bounds(), vp, Projection::default(), 32, 32);
        let key = |code: &str| cache_key_for(code, mesh.content_hash(), &optics, &cam);
        assert_eq!(key(CODE_HASH), key(CODE_HASH), "the key is a pure function");
        assert_eq!(key(CODE_HASH), cache_key(&mesh, &optics, &cam));
        // Any other code hash (one changed character) gives another key, so a changed
        // reference never reads images its predecessor cached.
        let mut other = CODE_HASH.to_string();
        let last = if other.ends_with('0') { "1" } else { "0" };
        other.replace_range(63.., last);
        assert_ne!(key(&other), key(CODE_HASH));
        assert_ne!(
            cache_key_for(CODE_HASH, "another mesh", &optics, &cam),
            key(CODE_HASH)
        );
    }
}
