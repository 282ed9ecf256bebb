//! OBJ reader on top of `tobj`: positions, faces (polygons triangulated by our ear clipper,
//! since tobj's own triangulation is a fan) and vertex normals when the file has them.
//! Materials (`mtllib`) are ignored: the `mesh` statement's current `f` applies.

use glam::Vec3;

use super::triangulate::triangulate;
use super::{MaterialId, Triangle};
use crate::error::{Error, Result};

pub fn parse(bytes: &[u8], name: &str) -> Result<Vec<Triangle>> {
    let opts = tobj::LoadOptions {
        single_index: false,
        triangulate: false,
        ignore_points: true,
        ignore_lines: true,
    };
    let mut reader = std::io::BufReader::new(bytes);
    // tobj reports no positions, so its errors name the file only.
    let (models, _) =
        tobj::load_obj_buf(&mut reader, &opts, |_| Err(tobj::LoadError::GenericFailure)).map_err(
            |e| Error::Scene {
                file: name.to_string(),
                msg: format!("invalid OBJ: {e}"),
            },
        )?;
    let mut tris = Vec::new();
    let mut poly = Vec::new();
    let mut idx = Vec::new();
    for m in &models {
        let mesh = &m.mesh;
        let pos = |i: u32| -> Result<Vec3> {
            let i = i as usize * 3;
            mesh.positions
                .get(i..i + 3)
                .map(|p| Vec3::new(p[0], p[1], p[2]))
                .ok_or_else(|| Error::Scene {
                    file: name.to_string(),
                    msg: format!("invalid OBJ: face refers to missing vertex {}", i / 3 + 1),
                })
        };
        let has_normals =
            !mesh.normals.is_empty() && mesh.normal_indices.len() == mesh.indices.len();
        let nrm = |i: u32| -> Vec3 {
            let i = i as usize * 3;
            mesh.normals
                .get(i..i + 3)
                .map(|p| Vec3::new(p[0], p[1], p[2]).normalize_or_zero())
                .unwrap_or(Vec3::ZERO)
        };
        let arities: Vec<u32> = if mesh.face_arities.is_empty() {
            vec![3; mesh.indices.len() / 3]
        } else {
            mesh.face_arities.clone()
        };
        let mut start = 0usize;
        for &k in &arities {
            let k = k as usize;
            let face = start..start + k;
            start += k;
            if face.end > mesh.indices.len() {
                break;
            }
            poly.clear();
            for &i in &mesh.indices[face.clone()] {
                poly.push(pos(i)?);
            }
            idx.clear();
            if !triangulate(&poly, &mut idx) {
                continue;
            }
            for &[a, b, c] in &idx {
                let corner = [a, b, c].map(|j| face.start + j as usize);
                let v = corner.map(|j| poly[j - face.start]);
                let n = has_normals
                    .then(|| corner.map(|j| nrm(mesh.normal_indices[j])))
                    .filter(|n| n.iter().all(|v| v.length_squared() > 0.0));
                tris.push(Triangle {
                    v,
                    n,
                    material: MaterialId(0),
                });
            }
        }
    }
    Ok(tris)
}
