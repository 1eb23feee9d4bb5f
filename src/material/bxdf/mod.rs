//! Scattering lobes: a closed set of small `Copy` BxDFs, each in a file of its own with its
//! value, density, sampling and albedo together, working in the local shading frame (z = shading
//! normal, on the side the light leaves towards the viewer for two-sided surfaces).
//!
//! Contract (pbrt-v4 `BxDF`, Mitsuba 3 `BSDF`): directions point away from the surface and are
//! unit vectors in the local frame; `wo` is towards the viewer (or where a photon came from), `wi`
//! the other direction. `f` excludes the cosine; `pdf` is per unit solid angle of `wi` and is 0
//! for delta lobes; `sample` returns the Monte Carlo weight f |cos wi| / pdf directly, and for a
//! delta lobe its discrete probability as `pdf`. Transport mode: radiance refracting into a denser
//! medium is scaled by 1 / eta^2, importance (photon flux) is not.
//!
//! Adding a lobe: a file with its struct and its `impl Lobe`, and its name in the `bxdfs!` list
//! below (under `out_of_line` unless it is as cheap as a Lambertian lobe), which makes the `Bxdf`
//! variant and every method's dispatch (there is no other `match` over the lobes to extend). Then add it to the chi-square, reciprocity and furnace tests in
//! `material/bsdf/tests.rs`.

mod coating;
mod coating_table;
mod conductor;
mod dielectric;
mod lambert;
mod mirror;
mod phong;
mod plastic_diffuse;
mod principled;
mod rough_coating;
mod rough_conductor;
mod rough_dielectric;
mod rough_plastic_diffuse;
mod transmission;

pub use coating::FresnelMirror;
pub use coating_table::{CoatingTable, TABLE_SIZE, gauss_legendre};
pub use conductor::Conductor;
pub use dielectric::Dielectric;
pub use lambert::Lambert;
pub use mirror::Mirror;
pub use phong::{Phong, sample_phong};
pub use plastic_diffuse::PlasticDiffuse;
pub use principled::{
    DiffuseTransmission, PrincipledClearcoat, PrincipledDiffuse, PrincipledSpecular, ThinSpecular, tint_of,
};
pub use rough_coating::RoughCoating;
pub use rough_conductor::RoughConductor;
pub use rough_dielectric::RoughDielectric;
pub use rough_plastic_diffuse::RoughPlasticDiffuse;
pub use transmission::Transmission;

use crate::math::{Color, Vec2, Vec3, luminance};

/// Which way light flows along the path being traced: camera paths carry radiance, photon paths
/// carry flux (importance). Refraction scales radiance by 1/eta^2 but not flux.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Transport {
    Radiance,
    Importance,
}

/// Kinds of scattering, as bits: reflection or transmission, diffuse, glossy or specular.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct LobeFlags(u8);

impl LobeFlags {
    pub const NONE: LobeFlags = LobeFlags(0);
    pub const REFLECTION: LobeFlags = LobeFlags(1);
    pub const TRANSMISSION: LobeFlags = LobeFlags(2);
    pub const DIFFUSE: LobeFlags = LobeFlags(4);
    pub const GLOSSY: LobeFlags = LobeFlags(8);
    pub const SPECULAR: LobeFlags = LobeFlags(16);
    pub const DIFFUSE_REFLECTION: LobeFlags = LobeFlags(1 | 4);
    pub const GLOSSY_REFLECTION: LobeFlags = LobeFlags(1 | 8);
    pub const SPECULAR_REFLECTION: LobeFlags = LobeFlags(1 | 16);
    pub const SPECULAR_TRANSMISSION: LobeFlags = LobeFlags(2 | 16);
    pub const GLOSSY_TRANSMISSION: LobeFlags = LobeFlags(2 | 8);
    /// Straight through without scattering (the transparent part of a `mask`).
    pub const NULL: LobeFlags = LobeFlags(32);

    /// True when every bit of `other` is set.
    #[inline]
    pub fn contains(self, other: LobeFlags) -> bool {
        self.0 & other.0 == other.0
    }

    /// True when any bit of `other` is set.
    #[inline]
    pub fn intersects(self, other: LobeFlags) -> bool {
        self.0 & other.0 != 0
    }

    /// A delta direction: specular scattering or passing straight through.
    #[inline]
    pub fn is_specular(self) -> bool {
        self.intersects(LobeFlags(16 | 32))
    }

    #[inline]
    pub fn is_null(self) -> bool {
        self.intersects(LobeFlags::NULL)
    }

    #[inline]
    pub fn is_diffuse(self) -> bool {
        self.intersects(LobeFlags::DIFFUSE)
    }

    #[inline]
    pub fn is_glossy(self) -> bool {
        self.intersects(LobeFlags::GLOSSY)
    }

    #[inline]
    pub fn is_transmission(self) -> bool {
        self.intersects(LobeFlags::TRANSMISSION)
    }
}

impl std::ops::BitOr for LobeFlags {
    type Output = LobeFlags;
    fn bitor(self, o: LobeFlags) -> LobeFlags {
        LobeFlags(self.0 | o.0)
    }
}

impl std::ops::BitOrAssign for LobeFlags {
    fn bitor_assign(&mut self, o: LobeFlags) {
        self.0 |= o.0;
    }
}

/// A direction sampled from one lobe, in the local frame.
#[derive(Clone, Copy, Debug)]
pub struct BxdfSample {
    pub wi: Vec3,
    /// f |cos wi| / pdf.
    pub weight: Color,
    /// Solid-angle density of `wi`, or for a delta lobe the probability of having chosen it.
    pub pdf: f32,
    pub flags: LobeFlags,
}

/// What every lobe provides (see the module's contract). Each method is required except the
/// two about view-dependent selection, which only a plastic's coating and base override.
pub trait Lobe: Copy {
    /// The lobe's choice among the others of a mixture depends on the viewing direction
    /// (`selection`): a plastic's coating in proportion to its reflectance, its base to its
    /// transmittance.
    const DIRECTIONAL: bool = false;

    /// Every kind of scattering the lobe can do.
    fn flags(&self) -> LobeFlags;

    /// The lobe looks the same however the surface is turned about its normal, so its frame's
    /// tangent may be any perpendicular direction.
    fn is_isotropic(&self) -> bool;

    /// How often this lobe is sampled relative to the others of a mixture: an estimate of its
    /// albedo (1 for a dielectric, which always reflects or transmits everything).
    fn sampling_weight(&self) -> f32;

    /// How much more or less likely the lobe is to be chosen when seen from `wo` (local); 1
    /// unless `DIRECTIONAL`.
    #[inline]
    fn selection(&self, _wo: Vec3) -> f32 {
        1.0
    }

    /// The lobe's albedo averaged over the colour channels (1 for a dielectric): photons pick
    /// lobes in proportion to it, as Jensen's Russian roulette does.
    fn mean_albedo(&self) -> f32;

    /// The albedo of a Lambertian lobe (whose value is it over pi in every direction above the
    /// surface); `None` for every other lobe.
    fn lambert_albedo(&self) -> Option<Color>;

    /// The lobe with its values (and so its albedo) scaled by `w` in [0, 1]: a blend's share.
    fn scaled(self, w: f32) -> Self;

    /// The lobe in spectral mode: its colours as spectra at the path's wavelengths `wl`, one per
    /// lane (`crate::spectrum::lanes`), and a dielectric's relative index times `eta_ratio` (the
    /// hero wavelength's index over the one the lobe was made with; 1 unless dispersive).
    fn lifted(self, wl: &crate::spectrum::Wavelengths, eta_ratio: f32) -> Self;

    /// The lobe's value for the pair, without the cosine (0 for delta lobes).
    fn f(&self, wo: Vec3, wi: Vec3, mode: Transport) -> Color;

    /// Solid-angle density with which `sample` picks `wi` (0 for delta lobes).
    fn pdf(&self, wo: Vec3, wi: Vec3, mode: Transport) -> f32;

    /// `f` and `pdf` together; lobes whose two share costly terms (microfacet distributions,
    /// Fresnel) work them out once.
    #[inline]
    fn eval(&self, wo: Vec3, wi: Vec3, mode: Transport) -> (Color, f32) {
        (self.f(wo, wi, mode), self.pdf(wo, wi, mode))
    }

    /// Samples `wi`: `uc` chooses between reflection and transmission where a lobe has both, `u`
    /// picks the direction.
    fn sample(&self, wo: Vec3, uc: f32, u: Vec2, mode: Transport) -> Option<BxdfSample>;
}

/// The closed set of lobes: the enum and its dispatch to each lobe's `Lobe` methods, from one
/// list of names. The lobes listed as `inline` (the cheap, common ones) are evaluated in the
/// caller's code; the others through a call of their own (`out_of_line`). Inlined together,
/// every arm's shared terms (half vectors, table indices) were hoisted above the dispatch and
/// worked out for every lobe: a Lambertian BSDF's evaluation cost about 380 instructions.
macro_rules! bxdfs {
    (inline: $($inl:ident),+ ; out_of_line: $($ool:ident),+ $(,)?) => {
        /// One scattering lobe.
        #[derive(Clone, Copy, Debug, PartialEq)]
        pub enum Bxdf {
            $($inl($inl),)+
            $($ool($ool)),+
        }

        $(impl From<$inl> for Bxdf {
            #[inline]
            fn from(b: $inl) -> Bxdf {
                Bxdf::$inl(b)
            }
        })+
        $(impl From<$ool> for Bxdf {
            #[inline]
            fn from(b: $ool) -> Bxdf {
                Bxdf::$ool(b)
            }
        })+

        impl Bxdf {
            #[inline]
            pub fn flags(&self) -> LobeFlags {
                match self { $(Bxdf::$inl(b) => b.flags(),)+ $(Bxdf::$ool(b) => b.flags()),+ }
            }

            /// See `Lobe::is_isotropic`.
            #[inline]
            pub fn is_isotropic(&self) -> bool {
                match self { $(Bxdf::$inl(b) => b.is_isotropic(),)+ $(Bxdf::$ool(b) => b.is_isotropic()),+ }
            }

            /// See `Lobe::sampling_weight`.
            #[inline]
            pub fn sampling_weight(&self) -> f32 {
                match self { $(Bxdf::$inl(b) => b.sampling_weight(),)+ $(Bxdf::$ool(b) => b.sampling_weight()),+ }
            }

            /// See `Lobe::selection`.
            #[inline]
            pub fn selection(&self, wo: Vec3) -> f32 {
                match self { $(Bxdf::$inl(b) => b.selection(wo),)+ $(Bxdf::$ool(b) => out_of_line::selection(b, wo)),+ }
            }

            /// True when the lobe's choice depends on the viewing direction (see `selection`).
            #[inline]
            pub fn directional_selection(&self) -> bool {
                match self {
                    $(Bxdf::$inl(_) => <$inl as Lobe>::DIRECTIONAL,)+
                    $(Bxdf::$ool(_) => <$ool as Lobe>::DIRECTIONAL),+
                }
            }

            /// See `Lobe::mean_albedo`.
            #[inline]
            pub fn mean_albedo(&self) -> f32 {
                match self { $(Bxdf::$inl(b) => b.mean_albedo(),)+ $(Bxdf::$ool(b) => b.mean_albedo()),+ }
            }

            /// See `Lobe::lambert_albedo`.
            #[inline]
            pub fn lambert_albedo(&self) -> Option<Color> {
                match self { $(Bxdf::$inl(b) => b.lambert_albedo(),)+ $(Bxdf::$ool(b) => b.lambert_albedo()),+ }
            }

            /// See `Lobe::scaled`.
            #[inline]
            pub fn scaled(self, w: f32) -> Bxdf {
                match self {
                    $(Bxdf::$inl(b) => Bxdf::$inl(b.scaled(w)),)+
                    $(Bxdf::$ool(b) => Bxdf::$ool(b.scaled(w))),+
                }
            }

            /// See `Lobe::lifted`.
            #[inline]
            pub fn lifted(self, wl: &crate::spectrum::Wavelengths, eta_ratio: f32) -> Bxdf {
                match self {
                    $(Bxdf::$inl(b) => Bxdf::$inl(b.lifted(wl, eta_ratio)),)+
                    $(Bxdf::$ool(b) => Bxdf::$ool(b.lifted(wl, eta_ratio))),+
                }
            }

            /// See `Lobe::f`.
            #[inline]
            pub fn f(&self, wo: Vec3, wi: Vec3, mode: Transport) -> Color {
                match self { $(Bxdf::$inl(b) => b.f(wo, wi, mode),)+ $(Bxdf::$ool(b) => out_of_line::f(b, wo, wi, mode)),+ }
            }

            /// See `Lobe::pdf`.
            #[inline]
            pub fn pdf(&self, wo: Vec3, wi: Vec3, mode: Transport) -> f32 {
                match self {
                    $(Bxdf::$inl(b) => b.pdf(wo, wi, mode),)+
                    $(Bxdf::$ool(b) => out_of_line::pdf(b, wo, wi, mode)),+
                }
            }

            /// See `Lobe::eval`.
            #[inline]
            pub fn eval(&self, wo: Vec3, wi: Vec3, mode: Transport) -> (Color, f32) {
                match self {
                    $(Bxdf::$inl(b) => b.eval(wo, wi, mode),)+
                    $(Bxdf::$ool(b) => out_of_line::eval(b, wo, wi, mode)),+
                }
            }

            /// See `Lobe::sample`.
            #[inline]
            pub fn sample(&self, wo: Vec3, uc: f32, u: Vec2, mode: Transport) -> Option<BxdfSample> {
                match self {
                    $(Bxdf::$inl(b) => b.sample(wo, uc, u, mode),)+
                    $(Bxdf::$ool(b) => out_of_line::sample(b, wo, uc, u, mode)),+
                }
            }
        }
    };
}

/// The methods of the lobes dispatched out of line: one function per lobe and method.
mod out_of_line {
    use super::{BxdfSample, Lobe, Transport};
    use crate::math::{Color, Vec2, Vec3};

    #[inline(never)]
    pub(super) fn selection<L: Lobe>(l: &L, wo: Vec3) -> f32 {
        l.selection(wo)
    }

    #[inline(never)]
    pub(super) fn f<L: Lobe>(l: &L, wo: Vec3, wi: Vec3, mode: Transport) -> Color {
        l.f(wo, wi, mode)
    }

    #[inline(never)]
    pub(super) fn pdf<L: Lobe>(l: &L, wo: Vec3, wi: Vec3, mode: Transport) -> f32 {
        l.pdf(wo, wi, mode)
    }

    #[inline(never)]
    pub(super) fn eval<L: Lobe>(l: &L, wo: Vec3, wi: Vec3, mode: Transport) -> (Color, f32) {
        l.eval(wo, wi, mode)
    }

    #[inline(never)]
    pub(super) fn sample<L: Lobe>(l: &L, wo: Vec3, uc: f32, u: Vec2, mode: Transport) -> Option<BxdfSample> {
        l.sample(wo, uc, u, mode)
    }
}

bxdfs!(
    inline: Lambert, Mirror, Transmission, Dielectric;
    out_of_line:
        Phong,
        Conductor,
        RoughConductor,
        RoughDielectric,
        FresnelMirror,
        PlasticDiffuse,
        RoughCoating,
        RoughPlasticDiffuse,
        PrincipledDiffuse,
        PrincipledSpecular,
        PrincipledClearcoat,
        DiffuseTransmission,
        ThinSpecular,
);

/// Mirror direction of `w` about the local normal (seed eq. 3 with I = -w).
#[inline]
pub fn reflect_local(w: Vec3) -> Vec3 {
    Vec3::new(-w.x, -w.y, w.z)
}

/// The half vector of a pair at an interface of relative index `eta`, turned to the +z side:
/// wo + wi for reflection, the generalised wo + eta wi for refraction (rough glass, principled).
#[inline]
pub fn half_vector(wo: Vec3, wi: Vec3, eta: f32, reflect: bool) -> Vec3 {
    let h = if reflect { wo + wi } else { wo + wi * eta };
    let h = h.normalize_or_zero();
    if h.z < 0.0 { -h } else { h }
}

/// The mirror direction of `w` about the facet normal `m`.
#[inline]
pub fn reflect_about(w: Vec3, m: Vec3) -> Vec3 {
    2.0 * w.dot(m) * m - w
}

/// Refracted direction of `wo` (local, on the +z side) into a medium of relative index `eta`
/// (seed eq. 4); `None` under total internal reflection.
#[inline]
pub fn refract_local(wo: Vec3, eta: f32) -> Option<Vec3> {
    super::fresnel::refract(-wo, Vec3::Z, eta)
}

/// The weight with which a lobe of reflectance `c` is chosen for sampling: its luminance, but
/// never below a tenth of its brightest channel (so a saturated colour is still sampled).
#[inline]
pub(crate) fn colour_weight(c: Color) -> f32 {
    luminance(c).max(c.max_element() * 0.1)
}
