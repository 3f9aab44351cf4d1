//! `epsm bench rays --dump DIR`: the sphere's triangles and ray sets as raw
//! little-endian `f32` files, for another ray tracer to walk the same rays
//! (`scripts/embree-compare.py`).

use std::io::Write;
use std::path::Path;

use anyhow::Context;
use epsm_render::Ray;
use epsm_render::scene::Object;

/// Writes `triangles.f32` (each object's triangles in world space, nine
/// `f32` per triangle), `coherent.f32` and `incoherent.f32` (six `f32` per
/// ray: origin, direction) into `dir`, creating it, each file atomically.
pub(super) fn write(
    dir: &Path,
    objects: &[Object],
    coherent: &[Ray],
    incoherent: &[Ray],
) -> anyhow::Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let triangles = objects.iter().flat_map(|o| {
        o.mesh.indices.iter().flat_map(move |tri| {
            tri.iter().flat_map(move |&v| {
                let p = o.mesh.positions[v as usize].as_dvec3();
                o.world_from_object.transform_point3(p).as_vec3().to_array()
            })
        })
    });
    save(&dir.join("triangles.f32"), triangles)?;
    for (name, rays) in [("coherent.f32", coherent), ("incoherent.f32", incoherent)] {
        let values = rays
            .iter()
            .flat_map(|r| r.origin.to_array().into_iter().chain(r.dir.to_array()));
        save(&dir.join(name), values)?;
    }
    Ok(())
}

/// Writes `values` to `path` as little-endian `f32`, atomically.
fn save(path: &Path, values: impl Iterator<Item = f32>) -> anyhow::Result<()> {
    epsm_scene::atomic_file::write_atomic(
        path,
        |e| anyhow::Error::new(e).context(format!("writing {}", path.display())),
        |out| {
            for v in values {
                out.write_all(&v.to_le_bytes())
                    .with_context(|| format!("writing {}", path.display()))?;
            }
            Ok(())
        },
    )
}
