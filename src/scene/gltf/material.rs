//! glTF's metallic-roughness materials on the Whitted model: one table, documented in
//! docs/scene-format.md ("glTF materials"), written here once; and their base colour
//! textures, read from a file beside the model, a data URI or a buffer view.

use std::path::Path;

use glam::{Affine2, Vec2, Vec3};
use gltf::texture::WrappingMode;

use super::buffers;
use crate::scene::images;
use crate::scene::io;
use crate::scene::model::{Material, Texture, Wrap};
use crate::util::limits::{MAX_IMAGE_BYTES, MAX_LIGHT};

/// glTF's texture coordinates put v = 0 at the image's top row, gpurt's at its bottom
/// (OBJ's convention): every TEXCOORD_0 is read through this flip.
pub const FLIP_V: Affine2 = Affine2::from_cols(Vec2::X, Vec2::NEG_Y, Vec2::Y);

/// Where a file's images come from: its buffers, and its folder for images named by
/// relative URIs (`None` for bytes that come from no file).
pub struct Images<'a> {
    pub file: &'a str,
    /// The file's JSON, where an image's source is checked before the crate reads it.
    pub json: &'a gltf::json::Root,
    pub buffers: &'a [Vec<u8>],
    pub dir: Option<&'a Path>,
}

impl Images<'_> {
    /// Material `m`'s base colour texture, an index into `textures` (read the first time
    /// a material names it), and the map of TEXCOORD_0 onto it: `KHR_texture_transform`
    /// (offset, rotation, scale as its specification's matrix), then `FLIP_V`. `None` for
    /// a material without one, and for one that cannot be had, with a warning naming the
    /// image and the material: its surfaces keep the material's colour.
    pub fn base_color(
        &self,
        m: &gltf::Material,
        textures: &mut Vec<Texture>,
        warnings: &mut Vec<String>,
    ) -> Option<(u32, Affine2)> {
        let info = m.pbr_metallic_roughness().base_color_texture()?;
        let image = info.texture().source();
        let what = format!(
            "{}: image {} (the base colour of material {})",
            self.file,
            image.index(),
            m.index().map_or("default".into(), |i| i.to_string())
        );
        let transform = info.texture_transform();
        let set = transform
            .as_ref()
            .and_then(|t| t.tex_coord())
            .unwrap_or(info.tex_coord());
        let mut read = || -> Result<u32, String> {
            if set != 0 {
                return Err(format!(
                    "it uses TEXCOORD_{set}, and gpurt reads TEXCOORD_0 only"
                ));
            }
            let sampler = info.texture().sampler();
            let wrap = [sampler.wrap_s(), sampler.wrap_t()].map(|w| match w {
                WrappingMode::ClampToEdge => Wrap::Clamp,
                WrappingMode::MirroredRepeat => Wrap::Mirror,
                WrappingMode::Repeat => Wrap::Repeat,
            });
            if let Some(i) = images::find(textures, &what, wrap) {
                return Ok(i);
            }
            let texture = images::decode(&self.bytes(&image)?, &what, wrap)?;
            Ok(images::add(textures, texture, warnings))
        };
        match read() {
            Ok(i) => {
                let uv = transform.map_or(Affine2::IDENTITY, |t| {
                    Affine2::from_scale_angle_translation(
                        Vec2::from(t.scale()),
                        t.rotation(),
                        Vec2::from(t.offset()),
                    )
                });
                Some((i, FLIP_V * uv))
            }
            Err(why) => {
                warnings.push(format!(
                    "{what} is not used: {why}; its surfaces keep the material's colour"
                ));
                None
            }
        }
    }

    /// The encoded bytes of `image`.
    fn bytes(&self, image: &gltf::Image) -> Result<Vec<u8>, String> {
        // The crate's `source` unwraps a buffer view's MIME type and, without a view, the
        // URI (gltf 1.4.1, `Image::source`); its validation requires neither.
        let json = &self.json.images[image.index()];
        match (&json.buffer_view, &json.mime_type, &json.uri) {
            (Some(_), None, _) => return Err("a buffer view without a mimeType".into()),
            (None, _, None) => return Err("neither a uri nor a buffer view".into()),
            _ => {}
        }
        match image.source() {
            gltf::image::Source::View { view, .. } => self
                .buffers
                .get(view.buffer().index())
                .and_then(|b| b.get(view.offset()..view.offset().checked_add(view.length())?))
                .map(<[u8]>::to_vec)
                .ok_or_else(|| format!("buffer view {} reaches past its buffer", view.index())),
            gltf::image::Source::Uri { uri, .. } => match uri.strip_prefix("data:") {
                Some(data) => buffers::data_uri(data),
                None => {
                    let rel = buffers::percent_decode(uri);
                    let dir = self.dir.ok_or_else(|| {
                        format!("'{rel}' must be given with the model, which is not a file")
                    })?;
                    io::read_inside(dir, &rel, MAX_IMAGE_BYTES)
                }
            },
        }
    }
}

/// The Whitted material of glTF material `m`:
///
/// - colour: the base colour factor's red, green and blue (alpha is not read);
/// - Ks, the highlight's weight and the mirror's: the Fresnel reflectance at normal
///   incidence, 0.04 for a dielectric and 1 for a metal, mixed by `metallic`, times
///   `1 - roughness` (a rough surface mirrors nothing);
/// - Kd: `1 - metallic` (metals have no diffuse term), less the light transmitted;
/// - Shine: the Blinn-Phong exponent of the same highlight width as GGX's roughness,
///   `2 / a^2 - 2` with `a = roughness^2`, between 1 and 10^4;
/// - T: `KHR_materials_transmission`'s factor; ior: `KHR_materials_ior`'s (1.5 without);
/// - emission: the emissive factor times `KHR_materials_emissive_strength`'s strength (1
///   without): the radiance of an emitter, whose triangles light the scene.
pub fn whitted(m: &gltf::Material) -> Material {
    let pbr = m.pbr_metallic_roughness();
    let (base, metallic, roughness) = (
        pbr.base_color_factor(),
        pbr.metallic_factor(),
        pbr.roughness_factor(),
    );
    let transmission = m.transmission().map_or(0.0, |t| t.transmission_factor());
    let ior = m.ior().unwrap_or(1.5);
    let strength = m.emissive_strength().unwrap_or(1.0);
    let clamp = |x: f32| {
        if x.is_finite() {
            x.clamp(0.0, 1.0)
        } else {
            0.0
        }
    };
    let (metallic, roughness, t) = (clamp(metallic), clamp(roughness), clamp(transmission));
    let reflect = 0.04 + 0.96 * metallic;
    let a = (roughness * roughness).max(1e-4);
    Material {
        color: Vec3::from_slice(&base[..3]).map(clamp),
        kd: (1.0 - metallic) * (1.0 - t),
        ks: reflect * (1.0 - roughness),
        shine: (2.0 / (a * a) - 2.0).clamp(1.0, 1e4),
        t,
        ior: if ior.is_finite() && ior >= 1.0 {
            ior
        } else {
            1.5
        },
        emission: (Vec3::from(m.emissive_factor()) * strength).map(|e| {
            if e.is_finite() {
                e.clamp(0.0, MAX_LIGHT)
            } else {
                0.0
            }
        }),
        texture: None,
        ambient: None,
    }
}
