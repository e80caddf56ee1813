//! The scanned appearance of the YCB objects: each visual mesh's texture map and the texture
//! coordinates of its triangles, in the triangle order of [`crate::ycb::load_mesh`], so that a
//! ray hit on the mesh (its triangle, `RayIntersection::subshape`, and the local hit point)
//! gives the colour the scanner saw there. The chips can has only a collision mesh and no
//! texture.

use crate::ycb::{Object, mesh, obj_load_options};
use crate::{Result, TestkitError};
use image::RgbImage;
use nalgebra::Point3;
use std::collections::HashMap;
use std::sync::{Arc, Mutex, OnceLock};

/// An object's texture map and per-triangle texture coordinates.
pub struct ObjectTexture {
    image: RgbImage,
    /// (u, v) of each triangle's three corners, OBJ convention (v up).
    uv: Vec<[[f32; 2]; 3]>,
}

impl ObjectTexture {
    /// The mean colour over the triangles (each read at its centroid): the flat colour a
    /// renderer without texture mapping (graspd-sim's MuJoCo geoms) gives the object.
    pub fn mean_colour(&self) -> [f64; 3] {
        let mut sum = [0.0; 3];
        for uv in &self.uv {
            let px = self.texel(
                (uv[0][0] + uv[1][0] + uv[2][0]) as f64 / 3.0,
                (uv[0][1] + uv[1][1] + uv[2][1]) as f64 / 3.0,
            );
            for (s, c) in sum.iter_mut().zip(px) {
                *s += c;
            }
        }
        sum.map(|s| s / self.uv.len().max(1) as f64)
    }

    /// The texel at texture coordinates (u, v), OBJ convention (v up), nearest.
    fn texel(&self, tu: f64, tv: f64) -> [f64; 3] {
        let (w, h) = self.image.dimensions();
        let x = ((tu.rem_euclid(1.0) * w as f64) as u32).min(w - 1);
        let y = (((1.0 - tv.rem_euclid(1.0)) * h as f64) as u32).min(h - 1);
        self.image.get_pixel(x, y).0.map(f64::from)
    }

    /// The colour (0…255) at local point `p` on triangle `triangle` of the object's mesh
    /// (barycentric interpolation of the corners' texture coordinates, nearest texel).
    pub fn colour(&self, object: Object, triangle: u32, p: &Point3<f64>) -> Option<[f64; 3]> {
        let m = mesh(object).ok()?;
        let i = triangle as usize;
        let uv = self.uv.get(i)?;
        let tri = m.triangle(triangle);
        let (a, b, c) = (
            Point3::new(tri.a.x, tri.a.y, tri.a.z),
            Point3::new(tri.b.x, tri.b.y, tri.b.z),
            Point3::new(tri.c.x, tri.c.y, tri.c.z),
        );
        let (v0, v1, v2) = (b - a, c - a, p - a);
        let (d00, d01, d11) = (v0.dot(&v0), v0.dot(&v1), v1.dot(&v1));
        let (d20, d21) = (v2.dot(&v0), v2.dot(&v1));
        let den = d00 * d11 - d01 * d01;
        if den.abs() < 1e-18 {
            return None;
        }
        let wb = ((d11 * d20 - d01 * d21) / den).clamp(0.0, 1.0);
        let wc = ((d00 * d21 - d01 * d20) / den).clamp(0.0, 1.0 - wb);
        let wa = 1.0 - wb - wc;
        let tu = wa * uv[0][0] as f64 + wb * uv[1][0] as f64 + wc * uv[2][0] as f64;
        let tv = wa * uv[0][1] as f64 + wb * uv[1][1] as f64 + wc * uv[2][1] as f64;
        Some(self.texel(tu, tv))
    }
}

/// Loads an object's texture (uncached; see [`texture`]); `None` for the chips can.
pub fn load_texture(object: Object) -> Result<Option<ObjectTexture>> {
    if object == Object::ChipsCan {
        return Ok(None);
    }
    let path = object.mesh_path();
    // The options of `ycb::load_mesh`, so that the triangles come in the same order.
    let (models, _) = tobj::load_obj(&path, &obj_load_options())
        .map_err(|e| TestkitError(format!("cannot load {} ({e})", path.display())))?;
    let mut uv = Vec::new();
    for m in &models {
        let (t, ti) = (&m.mesh.texcoords, &m.mesh.texcoord_indices);
        if ti.len() != m.mesh.indices.len() {
            return Err(TestkitError(format!(
                "{}: a face without texture coordinates",
                path.display()
            )));
        }
        let at = |k: u32| [t[2 * k as usize], t[2 * k as usize + 1]];
        uv.extend(ti.chunks_exact(3).map(|c| [at(c[0]), at(c[1]), at(c[2])]));
    }
    let image_path = path.with_file_name("texture_map.png");
    let image = image::open(&image_path)
        .map_err(|e| TestkitError(format!("{}: {e}", image_path.display())))?
        .to_rgb8();
    Ok(Some(ObjectTexture { image, uv }))
}

/// The object's texture, loaded once per process and shared (`None` for the chips can).
pub fn texture(object: Object) -> Result<Option<Arc<ObjectTexture>>> {
    type Cache = Mutex<HashMap<Object, Option<Arc<ObjectTexture>>>>;
    static CACHE: OnceLock<Cache> = OnceLock::new();
    let cache = CACHE.get_or_init(|| Mutex::new(HashMap::new()));
    let mut map = cache.lock().unwrap_or_else(|p| p.into_inner());
    if let Some(t) = map.get(&object) {
        return Ok(t.clone());
    }
    let t = load_texture(object)?.map(Arc::new);
    map.insert(object, t.clone());
    Ok(t)
}

#[cfg(test)]
mod tests {
    use super::*;
    use parry3d_f64::math::Vector;
    use parry3d_f64::query::{Ray, RayCast};

    /// The mustard bottle is yellow all over: rays into its side, at every height, see yellow
    /// texels (a wrong triangle order or a flipped v would read the white cap or the atlas's
    /// black padding).
    #[test]
    fn mustard_bottle_is_yellow() {
        let o = Object::MustardBottle;
        let m = mesh(o).unwrap();
        let t = texture(o).unwrap().unwrap();
        assert_eq!(t.uv.len(), m.num_triangles());
        let aabb = m.local_aabb();
        let c = aabb.center();
        for k in 1..10 {
            let z = aabb.mins.z + (aabb.maxs.z - aabb.mins.z) * k as f64 / 12.0;
            let ray = Ray::new(Vector::new(c.x - 0.3, c.y, z), Vector::new(1.0, 0.0, 0.0));
            let hit = m.cast_local_ray_and_get_normal(&ray, 1.0, false).unwrap();
            let p = ray.point_at(hit.time_of_impact);
            let [r, g, b] = t
                .colour(o, hit.subshape, &Point3::new(p.x, p.y, p.z))
                .unwrap();
            assert!(
                r > 150.0 && g > 110.0 && b < 0.5 * g,
                "not yellow at z = {z:.3}: {:?}",
                [r, g, b]
            );
        }
        assert!(texture(Object::ChipsCan).unwrap().is_none());
    }
}
