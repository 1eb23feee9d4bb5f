//! Environment lights from scene files: an image read by `texture::image` becomes a shared
//! `EnvMap`, oriented by the file's transform. Both loaders use this, so a TOML scene and its
//! Mitsuba twin get the same light.

use crate::geometry::Transform;
use crate::light::{EnvMap, Environment};
use crate::math::{Color, Frame, Vec3};
use crate::texture::image::TexImage;

/// The environment light of `image` (linear texels, row 0 at the top) times `scale`, turned by
/// `transform`'s rotation (a uniform scale is allowed and ignored, translations do nothing; a
/// shear or non-uniform scale is refused, as it has no meaning for directions).
pub fn environment_map(image: &TexImage, scale: f32, transform: &Transform) -> Result<Environment, String> {
    if !transform.is_valid() || !transform.is_similarity() {
        return Err("an environment map's transform may only rotate (and scale uniformly)".into());
    }
    let c = image.channels as usize;
    let texels: Vec<Color> = image
        .texels
        .chunks_exact(c)
        .map(|t| if c >= 3 { Color::new(t[0], t[1], t[2]) } else { Color::splat(t[0]) })
        .collect();
    let map = EnvMap::shared(image.width, image.height, texels)?;
    let axis = |v: Vec3| transform.vector(v).normalize();
    let frame = Frame { x: axis(Vec3::X), y: axis(Vec3::Y), z: axis(Vec3::Z) };
    Ok(Environment::map(map, scale, frame))
}
