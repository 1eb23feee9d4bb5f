//! The plugins Mitsuba 3 (3.9) ships, by the kind of object they make: a `type` Mitsuba knows
//! but caustic does not render is a warning (an error with `--strict`), and one Mitsuba would
//! refuse too (a misspelling) is an error naming the nearest known type, as Mitsuba stops on it.
//! docs/mitsuba.md lists what each is rendered as.

use super::props::closest;

/// What a plugin makes (the element it is the `type` of).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PluginKind {
    Bsdf,
    Emitter,
    Shape,
    Texture,
    Integrator,
    Sensor,
    Filter,
    Sampler,
    Film,
    Medium,
    Phase,
    Volume,
    Spectrum,
}

impl PluginKind {
    /// Every plugin of this kind Mitsuba 3 has.
    pub fn plugins(self) -> &'static [&'static str] {
        match self {
            PluginKind::Bsdf => &[
                "blendbsdf",
                "bumpmap",
                "circular",
                "conductor",
                "dielectric",
                "diffuse",
                "hair",
                "mask",
                "measured",
                "measured_polarized",
                "normalmap",
                "null",
                "plastic",
                "polarizer",
                "pplastic",
                "principled",
                "principledthin",
                "retarder",
                "roughconductor",
                "roughdielectric",
                "roughplastic",
                "thindielectric",
                "twosided",
            ],
            PluginKind::Emitter => &[
                "area",
                "constant",
                "directional",
                "directionalarea",
                "envmap",
                "point",
                "projector",
                "spot",
                "sunsky",
            ],
            PluginKind::Shape => &[
                "bsplinecurve",
                "cube",
                "cylinder",
                "disk",
                "ellipsoids",
                "ellipsoidsmesh",
                "instance",
                "linearcurve",
                "merge",
                "obj",
                "ply",
                "rectangle",
                "sdfgrid",
                "serialized",
                "shapegroup",
                "sphere",
            ],
            PluginKind::Texture => &["bitmap", "checkerboard", "mesh_attribute", "volume"],
            PluginKind::Integrator => &[
                "aov",
                "depth",
                "direct",
                "direct_projective",
                "moment",
                "path",
                "prb",
                "prb_basic",
                "prb_projective",
                "prbvolpath",
                "ptracer",
                "stokes",
                "volpath",
                "volpathmis",
            ],
            PluginKind::Sensor => {
                &["batch", "distant", "irradiancemeter", "orthographic", "perspective", "radiancemeter", "thinlens"]
            }
            PluginKind::Filter => &["box", "catmullrom", "gaussian", "lanczos", "mitchell", "tent"],
            PluginKind::Sampler => &["independent", "ldsampler", "multijitter", "orthogonal", "stratified"],
            PluginKind::Film => &["hdrfilm", "specfilm"],
            PluginKind::Medium => &["heterogeneous", "homogeneous"],
            PluginKind::Phase => &["blendphase", "hg", "isotropic", "rayleigh", "sggx", "tabphase"],
            PluginKind::Volume => &["constvolume", "gridvolume"],
            PluginKind::Spectrum => &["blackbody", "d65", "irregular", "regular", "srgb", "uniform"],
        }
    }

    /// The word for the kind in messages.
    pub fn word(self) -> &'static str {
        match self {
            PluginKind::Bsdf => "BSDF",
            PluginKind::Emitter => "emitter",
            PluginKind::Shape => "shape",
            PluginKind::Texture => "texture",
            PluginKind::Integrator => "integrator",
            PluginKind::Sensor => "sensor",
            PluginKind::Filter => "reconstruction filter",
            PluginKind::Sampler => "sampler",
            PluginKind::Film => "film",
            PluginKind::Medium => "medium",
            PluginKind::Phase => "phase function",
            PluginKind::Volume => "volume",
            PluginKind::Spectrum => "spectrum",
        }
    }
}

/// `None` when Mitsuba 3 has a plugin `name` of this kind; otherwise the message of the error
/// (with the nearest known name, when one is near).
pub fn unknown(kind: PluginKind, name: &str) -> Option<String> {
    let known = kind.plugins();
    if known.contains(&name) {
        return None;
    }
    let hint = match closest(name, known.iter().copied()) {
        Some(k) => format!(" (did you mean `{k}`?)"),
        None => format!("; Mitsuba 3's are: {}", known.join(", ")),
    };
    Some(format!("unknown {} type `{name}`{hint}", kind.word()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn misspellings_name_the_nearest_plugin_and_known_ones_pass() {
        assert_eq!(unknown(PluginKind::Bsdf, "principled"), None);
        assert_eq!(
            unknown(PluginKind::Bsdf, "dielectrc").as_deref(),
            Some("unknown BSDF type `dielectrc` (did you mean `dielectric`?)")
        );
        assert_eq!(
            unknown(PluginKind::Shape, "sphre").as_deref(),
            Some("unknown shape type `sphre` (did you mean `sphere`?)")
        );
        let far = unknown(PluginKind::Film, "xyz").unwrap();
        assert!(far.contains("Mitsuba 3's are: hdrfilm, specfilm"), "{far}");
    }
}
