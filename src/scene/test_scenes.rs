//! Scenes for unit tests, built from TOML text with the default options.

use super::Scene;

/// The scene `text` (caustic's TOML) describes.
pub fn from_toml(text: &str) -> Scene {
    let mut desc = super::load_scene_str(text, "test.toml", std::path::Path::new(".")).unwrap();
    desc.apply(&crate::options::Options::default());
    desc.build().unwrap().scene
}

/// One 2 x 2 quad of material `material` (its TOML table's body) in the plane z = 0, facing
/// +z, under a point light at (0, 0, 2), seen from (0, 0, 3).
pub fn quad_of(material: &str) -> Scene {
    from_toml(&format!(
        r#"
[camera]
eye = [0, 0, 3]
look_at = [0, 0, 0]
[materials.m]
{material}
[[lights]]
type = "point"
position = [0, 0, 2]
[[objects]]
type = "quad"
corner = [-1, -1, 0]
edge1 = [2, 0, 0]
edge2 = [0, 2, 0]
material = "m"
"#
    ))
}
