//! The BSDF at a surface point: a weighted sum of up to `MAX_LOBES` lobes (`bxdf`) in the hit's
//! shading frame, oriented to the side the viewer is on. The physical integrators (path tracing,
//! photon mapping, SPPM) scatter through it; the Whitted integrator keeps the seed report's
//! classic model.
//!
//! Directions are in world space and point away from the surface; `wo` towards the viewer (or
//! where a photon came from), `wi` the other direction. Densities are per unit solid angle.
//! Sampling picks a lobe in proportion to its sampling weight (times its `selection` for the
//! viewing direction); a non-delta sample is weighted by the whole BSDF's value and density (so
//! lobes combine like one mixture), a delta sample by its own lobe over the probability of having
//! picked it.
//!
//! Two things wrap the lobes: an opacity (Mitsuba's `mask`: with probability 1 - opacity light
//! passes straight through, and the lobes are scaled by the opacity) and a perturbed shading
//! normal (bump and normal maps), which keeps the unperturbed normal to refuse directions that
//! change sides and to apply the shadow-terminator term of Estevez et al. (2019) as Mitsuba 3
//! does.

use super::bxdf::{Bxdf, BxdfSample, LobeFlags, Transport};
use super::given::{self, GivenSpectrum, LobeSpectra, NO_LOBE_SPECTRA};
use crate::math::{Color, Frame, Vec2, Vec3};

/// Most lobes a BSDF holds.
pub const MAX_LOBES: usize = 4;

/// A sampled direction with its Monte Carlo weight.
#[derive(Clone, Copy, Debug)]
pub struct BsdfSample {
    pub wi: Vec3,
    /// f |cos| / pdf: the throughput multiplier of this sample.
    pub weight: Color,
    /// Density of `wi` (0 for delta samples, whose density is a delta).
    pub pdf: f32,
    pub flags: LobeFlags,
}

/// A BSDF of one Lambertian lobe at one point (`Bsdf::one_lambert`).
#[derive(Clone, Copy, Debug)]
pub struct OneLambert {
    /// Shading and geometric normals on the viewer's side.
    n: Vec3,
    ng: Vec3,
    /// The albedo, and the value above the surface, opacity included.
    r: Color,
    f: Color,
    opacity: f32,
}

impl OneLambert {
    /// `Bsdf::eval(wo, wi, mode)` of the BSDF it was made from, for any `wo` and `mode`.
    #[inline(always)]
    pub fn eval(&self, wi: Vec3) -> (Color, f32) {
        if self.above(wi) { (self.f, self.pdf(wi)) } else { (Color::ZERO, 0.0) }
    }

    /// `Bsdf::pdf(wo, wi, mode)`.
    #[inline(always)]
    pub fn pdf(&self, wi: Vec3) -> f32 {
        if self.above(wi) { wi.dot(self.n) * std::f32::consts::FRAC_1_PI * self.opacity } else { 0.0 }
    }

    /// `wi` is above both normals (reflection, and the lobe's upper hemisphere).
    #[inline(always)]
    fn above(&self, wi: Vec3) -> bool {
        wi.dot(self.ng) > 0.0 && wi.dot(self.n) > 0.0
    }
}

/// The lobes of a material at a hit, with their sampling weights: what a material evaluates to
/// before it is placed in a shading frame. Materials without textures give the same lobes at
/// every hit, so the scene makes them once per material and side.
#[derive(Clone, Copy, Debug)]
pub struct Lobes {
    lobes: [Bxdf; MAX_LOBES],
    /// Each lobe's flags, kept beside it so that the loops over lobes need not dispatch on the
    /// lobe's kind to learn whether it applies.
    lobe_flags: [LobeFlags; MAX_LOBES],
    /// Sampling weight of each lobe for camera paths (luminance of its albedo).
    weights: [f32; MAX_LOBES],
    /// Sampling weight of each lobe for photons (its albedo averaged over the channels).
    photon_weights: [f32; MAX_LOBES],
    total: f32,
    photon_total: f32,
    count: u8,
    flags: LobeFlags,
    /// The spectra given for each lobe's colours (`super::given`), which spectral mode
    /// evaluates instead of lifting the colours; RGB mode never reads them.
    spectra: [LobeSpectra; MAX_LOBES],
    /// Every lobe is isotropic (see `Bxdf::is_isotropic`).
    isotropic: bool,
    /// Some lobe's choice depends on the viewing direction (`Bxdf::selection`).
    directional: bool,
    /// The lobes are one Lambertian lobe with a positive, finite weight (`Bsdf::one_lambert`).
    one_lambert: bool,
}

impl Default for Lobes {
    fn default() -> Self {
        let none = Bxdf::Lambert(super::bxdf::Lambert { r: Color::ZERO });
        Lobes {
            lobes: [none; MAX_LOBES],
            lobe_flags: [LobeFlags::NONE; MAX_LOBES],
            weights: [0.0; MAX_LOBES],
            photon_weights: [0.0; MAX_LOBES],
            total: 0.0,
            photon_total: 0.0,
            count: 0,
            flags: LobeFlags::NONE,
            spectra: [NO_LOBE_SPECTRA; MAX_LOBES],
            isotropic: true,
            directional: false,
            one_lambert: false,
        }
    }
}

impl Lobes {
    /// Adds a lobe; lobes that never scatter (zero sampling weight) are left out.
    #[inline]
    pub fn add(&mut self, lobe: Bxdf) {
        self.add_given(lobe, NO_LOBE_SPECTRA);
    }

    /// `add`, with the spectra given for the lobe's colours.
    #[inline]
    pub fn add_given(&mut self, lobe: Bxdf, spectra: LobeSpectra) {
        let w = lobe.sampling_weight();
        if !(w > 0.0) || self.count as usize >= MAX_LOBES {
            return;
        }
        let i = self.count as usize;
        self.lobes[i] = lobe;
        self.spectra[i] = spectra;
        self.lobe_flags[i] = lobe.flags();
        self.weights[i] = w;
        self.photon_weights[i] = lobe.mean_albedo().max(w * 1e-3);
        self.total += w;
        self.photon_total += self.photon_weights[i];
        self.count += 1;
        self.flags |= self.lobe_flags[i];
        self.isotropic &= lobe.is_isotropic();
        self.directional |= lobe.directional_selection();
        self.one_lambert = self.count == 1
            && matches!(self.lobes[0], Bxdf::Lambert(_))
            && !self.directional
            && self.total > 0.0
            && self.total.is_finite();
    }

    /// The lobes in spectral mode (`Lobe::lifted`): colours as spectra at `wl` (the spectra
    /// given for them, from `table`, or else their lifts), dielectric indices times
    /// `eta_ratio`; sampling weights follow the lifted values.
    #[inline]
    pub fn lifted(&self, wl: &crate::spectrum::Wavelengths, eta_ratio: f32, table: &[GivenSpectrum]) -> Lobes {
        let mut out = Lobes::default();
        for (lobe, ids) in self.as_slice().iter().zip(&self.spectra) {
            out.add(given::lifted(*lobe, ids, table, wl, eta_ratio));
        }
        out
    }

    /// Adds every lobe of `other`, each scaled by `w` (a blend of two materials).
    pub fn add_scaled(&mut self, other: &Lobes, w: f32) {
        for (lobe, ids) in other.as_slice().iter().zip(&other.spectra) {
            self.add_given(lobe.scaled(w), *ids);
        }
    }

    /// True when there is no lobe at all (a black surface, or the back of a one-sided one).
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.count == 0
    }

    /// Number of lobes held.
    #[inline]
    pub fn len(&self) -> usize {
        self.count as usize
    }

    /// True when every lobe is isotropic: the BSDF's frame then needs only the normal.
    #[inline]
    pub fn is_isotropic(&self) -> bool {
        self.isotropic
    }

    #[inline]
    pub(crate) fn as_slice(&self) -> &[Bxdf] {
        &self.lobes[..self.count as usize]
    }
}

/// The lobes a BSDF holds: a material's own lobes, shared by every hit on it (a hit costs a
/// pointer, not a 240-byte copy), or lobes made for this hit (textures, blends, wrappers).
/// Owned lobes stay inline: boxing them would allocate per hit.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Copy, Debug)]
pub enum LobeSet<'a> {
    Shared(&'a Lobes),
    Owned(Lobes),
}

impl std::ops::Deref for LobeSet<'_> {
    type Target = Lobes;
    #[inline(always)]
    fn deref(&self) -> &Lobes {
        match self {
            LobeSet::Shared(l) => l,
            LobeSet::Owned(l) => l,
        }
    }
}

/// A material's scattering at one hit: its lobes in the hit's shading frame, oriented to the
/// side the viewer is on.
#[derive(Clone, Copy, Debug)]
pub struct Bsdf<'a> {
    /// Shading frame; z is the shading normal on the side of `wo`.
    frame: Frame,
    /// Geometric normal on the same side.
    ng: Vec3,
    lobes: LobeSet<'a>,
    /// Probability of scattering at all; with 1 - opacity light passes straight through.
    opacity: f32,
    /// For a perturbed normal: the unperturbed shading normal (on the side of `wo`) and the
    /// shadow-terminator roughness alpha^2 of the perturbation.
    perturbed: Option<(Vec3, f32)>,
}

/// True when `wo` is on the outward side of a surface with geometric normal `ng` (a BSDF is
/// made for the side the viewer is on: `Bsdf::new` and the material's lobes must agree).
#[inline]
pub fn front_side(wo: Vec3, ng: Vec3) -> bool {
    wo.dot(ng) >= 0.0
}

impl<'a> Bsdf<'a> {
    /// The BSDF with `lobes` in `frame` (shading frame of the hit, z = shading normal) with
    /// geometric normal `ng`, both outward; they are turned to the viewer's side when `front`
    /// (see `front_side`) is false (two-sided surfaces).
    #[inline]
    pub fn new(frame: Frame, ng: Vec3, front: bool, lobes: Lobes) -> Self {
        Self::with_lobes(frame, ng, front, LobeSet::Owned(lobes))
    }

    /// `new` with the material's own lobes, shared (no copy).
    #[inline(always)]
    pub fn shared(frame: Frame, ng: Vec3, front: bool, lobes: &'a Lobes) -> Self {
        let (frame, ng) = if front { (frame, ng) } else { (frame.flipped(), -ng) };
        Bsdf { frame, ng, lobes: LobeSet::Shared(lobes), opacity: 1.0, perturbed: None }
    }

    /// `new` with lobes that may be shared with the material.
    #[inline]
    pub fn with_lobes(frame: Frame, ng: Vec3, front: bool, lobes: LobeSet<'a>) -> Self {
        let (frame, ng) = if front { (frame, ng) } else { (frame.flipped(), -ng) };
        Bsdf { frame, ng, lobes, opacity: 1.0, perturbed: None }
    }

    /// The same BSDF scattering with probability `opacity` and passing light straight through
    /// otherwise.
    #[inline]
    pub fn with_opacity(mut self, opacity: f32) -> Self {
        self.opacity = if opacity.is_finite() { opacity.clamp(0.0, 1.0) } else { 1.0 };
        self
    }

    /// The same BSDF in spectral mode: its lobes lifted (`Lobes::lifted`), owned.
    #[inline]
    pub fn lifted(self, wl: &crate::spectrum::Wavelengths, eta_ratio: f32, table: &[GivenSpectrum]) -> Self {
        Bsdf { lobes: LobeSet::Owned(self.lobes.lifted(wl, eta_ratio, table)), ..self }
    }

    /// The shading frame (z on the side of `wo`).
    #[inline]
    pub fn frame(&self) -> &Frame {
        &self.frame
    }

    /// Replaces the shading frame by `frame` (z on the side of `wo`), a perturbation of the
    /// current one by a bump or normal map. Directions that the perturbation moves to the other
    /// side of the unperturbed normal are refused, and light arriving at a grazing angle of the
    /// unperturbed surface is shadowed by the terminator term.
    pub fn perturbed(mut self, frame: Frame) -> Self {
        let old = self.frame.z;
        // alpha^2 = min(tan^2 of the perturbation / 8, 1) (Estevez et al. 2019).
        let cos = frame.z.dot(old).clamp(-1.0, 1.0);
        let tan2 = (1.0 - cos * cos).max(0.0) / (cos * cos).max(1e-12);
        self.perturbed = Some((old, (0.125 * tan2).min(1.0)));
        self.frame = frame;
        self
    }

    /// The perturbation's factor for light direction `wi` (1 without a perturbation): 0 when
    /// `wi` changes side, else the shadow-terminator term.
    #[inline]
    fn perturbation(&self, wi: Vec3) -> f32 {
        let Some((old, alpha2)) = self.perturbed else { return 1.0 };
        let (c_old, c_new) = (wi.dot(old), wi.dot(self.frame.z));
        if c_old * c_new <= 0.0 {
            return 0.0;
        }
        let c2 = c_old * c_old;
        let tan2 = (1.0 - c2).max(0.0) / c2.max(1e-12);
        2.0 / (1.0 + (1.0 + alpha2 * tan2).sqrt())
    }

    /// The perturbation's factor for the pair (`wo`, `wi`) in transport `mode`: it belongs to
    /// the direction light arrives from, `wi` for radiance and `wo` for importance, so that
    /// `f(wo, wi, Importance) = f(wi, wo, Radiance)` (the adjoint BSDF light paths and photons
    /// need; with the factor on `wi` in both modes, light tracing a bump-mapped surface read
    /// +1.5% against the path tracer). Sampling and densities follow the same direction.
    #[inline]
    fn perturbation_of(&self, wo: Vec3, wi: Vec3, mode: Transport) -> f32 {
        match mode {
            Transport::Radiance => self.perturbation(wi),
            Transport::Importance => self.perturbation(wo),
        }
    }

    #[inline]
    fn lobes(&self) -> &[Bxdf] {
        self.lobes.as_slice()
    }

    /// True when the surface scatters nothing: no lobe and no transparent part (a plain emitter,
    /// or the back of a one-sided material).
    #[inline]
    pub fn is_black(&self) -> bool {
        self.lobes.count == 0 && self.opacity >= 1.0
    }

    /// The shading normal on the viewer's side.
    #[inline]
    pub fn normal(&self) -> Vec3 {
        self.frame.z
    }

    /// True when light passes straight through everywhere (a `null` boundary, a mask of
    /// opacity 0): the surface scatters nothing.
    #[inline]
    pub fn is_invisible(&self) -> bool {
        self.opacity == 0.0
    }

    /// The geometric normal on the viewer's side.
    #[inline]
    pub fn geometric_normal(&self) -> Vec3 {
        self.ng
    }

    /// Every kind of scattering the BSDF has.
    #[inline]
    pub fn flags(&self) -> LobeFlags {
        self.lobes.flags
    }

    /// True when every lobe is a delta (mirror, glass) or there is none: nothing to shade with
    /// light samples.
    #[inline]
    pub fn is_specular_only(&self) -> bool {
        !self.lobes.flags.intersects(LobeFlags::DIFFUSE | LobeFlags::GLOSSY) || self.opacity == 0.0
    }

    /// Albedo of the Lambertian lobes.
    pub fn diffuse_albedo(&self) -> Color {
        self.lobes().iter().filter_map(Bxdf::lambert_albedo).sum()
    }

    /// The lobes with their flags.
    #[inline(always)]
    fn lobes_with_flags(&self) -> impl Iterator<Item = (&Bxdf, LobeFlags)> {
        let n = self.lobes.count as usize;
        self.lobes.lobes[..n].iter().zip(self.lobes.lobe_flags[..n].iter().copied())
    }

    /// The kind of scattering that joins `wi` to the viewer: reflection when `wi` is on the
    /// viewer's side of the geometric surface, transmission otherwise.
    #[inline(always)]
    fn kind(&self, wi: Vec3) -> LobeFlags {
        if wi.dot(self.ng) > 0.0 { LobeFlags::REFLECTION } else { LobeFlags::TRANSMISSION }
    }

    /// The BSDF's value for the pair (no cosine): the non-delta lobes of the kind the geometry
    /// gives (reflection when `wi` is on the viewer's side of the surface).
    #[inline]
    pub fn f(&self, wo: Vec3, wi: Vec3, mode: Transport) -> Color {
        match self.one_lambert() {
            Some(one) => one.eval(wi).0,
            None => self.f_lobes(wo, wi, mode),
        }
    }

    /// `f` lobe by lobe.
    #[inline]
    fn f_lobes(&self, wo: Vec3, wi: Vec3, mode: Transport) -> Color {
        let kind = self.kind(wi);
        let (wo_l, wi_l) = (self.frame.to_local(wo), self.frame.to_local(wi));
        let mut f = Color::ZERO;
        for (lobe, flags) in self.lobes_with_flags() {
            if flags.intersects(kind) && !flags.is_specular() {
                f += lobe.f(wo_l, wi_l, mode);
            }
        }
        f * (self.opacity * self.perturbation_of(wo, wi, mode))
    }

    /// `f` and `pdf` of the pair at once (one change of frame, one pass over the lobes, and
    /// each lobe's shared terms worked out once): what next-event estimation with multiple
    /// importance sampling and mixture sampling both need.
    #[inline]
    pub fn eval(&self, wo: Vec3, wi: Vec3, mode: Transport) -> (Color, f32) {
        match self.one_lambert() {
            Some(one) => one.eval(wi),
            None => self.eval_lobes(wo, wi, mode),
        }
    }

    /// `eval` lobe by lobe.
    #[inline]
    fn eval_lobes(&self, wo: Vec3, wi: Vec3, mode: Transport) -> (Color, f32) {
        let kind = self.kind(wi);
        let (wo_l, wi_l) = (self.frame.to_local(wo), self.frame.to_local(wi));
        let (weights, total) = self.selection_weights(&self.lobes.weights, self.lobes.total, wo_l);
        let mut f = Color::ZERO;
        let mut pdf = 0.0;
        for ((lobe, flags), w) in self.lobes_with_flags().zip(&weights) {
            if flags.intersects(kind) && !flags.is_specular() {
                let (lf, lp) = lobe.eval(wo_l, wi_l, mode);
                f += lf;
                if total > 0.0 {
                    pdf += w / total * lp;
                }
            }
        }
        let p = self.perturbation_of(wo, wi, mode);
        let pdf = if total > 0.0 && p != 0.0 { pdf * self.opacity } else { 0.0 };
        (f * (self.opacity * p), pdf)
    }

    /// Each lobe's probability of being chosen, for lobe weights `base` (camera or photon) seen
    /// from `wo_l`, and their sum.
    #[inline(always)]
    fn selection_weights(&self, base: &[f32; MAX_LOBES], total: f32, wo_l: Vec3) -> ([f32; MAX_LOBES], f32) {
        if !self.lobes.directional {
            return (*base, total);
        }
        let mut w = [0.0; MAX_LOBES];
        let mut sum = 0.0;
        for (i, lobe) in self.lobes().iter().enumerate() {
            w[i] = base[i] * lobe.selection(wo_l);
            sum += w[i];
        }
        (w, sum)
    }

    /// Density with which `sample` picks `wi` through its non-delta lobes.
    #[inline]
    pub fn pdf(&self, wo: Vec3, wi: Vec3, mode: Transport) -> f32 {
        match self.one_lambert() {
            Some(one) => one.pdf(wi),
            None => self.pdf_lobes(wo, wi, mode),
        }
    }

    /// `pdf` lobe by lobe.
    #[inline]
    fn pdf_lobes(&self, wo: Vec3, wi: Vec3, mode: Transport) -> f32 {
        let kind = self.kind(wi);
        let (wo_l, wi_l) = (self.frame.to_local(wo), self.frame.to_local(wi));
        let (weights, total) = self.selection_weights(&self.lobes.weights, self.lobes.total, wo_l);
        if !(total > 0.0) || self.perturbation_of(wo, wi, mode) == 0.0 {
            return 0.0;
        }
        let mut pdf = 0.0;
        for ((lobe, flags), w) in self.lobes_with_flags().zip(&weights) {
            if flags.intersects(kind) && !flags.is_specular() {
                pdf += w / total * lobe.pdf(wo_l, wi_l, mode);
            }
        }
        pdf * self.opacity
    }

    /// The reverse of `pdf(wo, wi)`: the density with which this surface, reached from `wi`,
    /// samples `wo` (bidirectional methods weigh each technique by the densities of both
    /// subpaths, so each vertex needs the density of the direction the other subpath would have
    /// sampled). When `wi` is on the viewer's side of the geometric surface (reflection) that is
    /// `pdf(wi, wo)` of these lobes. `None` when `wi` is across the surface: seen from there the
    /// surface has other lobes (a dielectric's inverted relative index, a one-sided material's
    /// back), so the caller asks the BSDF made for `wi` (`Scene::bsdf(hit, wi).pdf(wi, wo)`).
    #[inline]
    pub fn pdf_reverse(&self, wo: Vec3, wi: Vec3, mode: Transport) -> Option<f32> {
        (wi.dot(self.ng) > 0.0).then(|| self.pdf(wi, wo, mode))
    }

    /// Picks a lobe in proportion to its sampling weight and samples it: (the lobe's sample in
    /// world space, the probability of the lobe). `uc` chooses the lobe and, rescaled, reflection
    /// or transmission within it; `u` the direction.
    #[inline(always)]
    fn sample_any_lobe(
        &self,
        base: &[f32; MAX_LOBES],
        base_total: f32,
        wo: Vec3,
        uc: f32,
        u: Vec2,
        mode: Transport,
    ) -> Option<(BxdfSample, f32)> {
        let n = self.lobes.count as usize;
        let wo_full = self.frame.to_local(wo);
        let (weights, total) = self.selection_weights(base, base_total, wo_full);
        let weights = &weights;
        if !(total > 0.0) {
            return None;
        }
        let (k, p_lobe, uc_lobe) = if n == 1 {
            (0, 1.0, uc)
        } else {
            let mut x = uc * total;
            let mut k = n - 1;
            for (i, &w) in weights[..n].iter().enumerate() {
                if x < w {
                    k = i;
                    break;
                }
                x -= w;
            }
            (k, weights[k] / total, (x / weights[k]).clamp(0.0, 1.0 - f32::EPSILON / 2.0))
        };
        let lobe = &self.lobes.lobes[k];
        let wo_l = wo_full;
        if wo_l.z <= 0.0 && !self.lobes.flags.is_transmission() {
            // Seen from below the shading normal, a surface that only reflects has nothing to give.
            return None;
        }
        let mut s = lobe.sample(wo_l, uc_lobe, u, mode)?;
        s.wi = self.frame.to_world(s.wi);
        // The side the direction leaves to must agree with the geometry, not only the shading
        // normal, or light would leak through the surface.
        let reflected = s.wi.dot(self.ng) > 0.0;
        if reflected == s.flags.is_transmission() {
            return None;
        }
        let p = self.perturbation_of(wo, s.wi, mode);
        if p == 0.0 {
            return None;
        }
        s.weight *= p;
        Some((s, p_lobe))
    }

    /// The straight-through sample of a mask's transparent part, when `uc` picks it; otherwise
    /// `uc` rescaled to choose among the lobes.
    #[inline(always)]
    fn pass_through(&self, wo: Vec3, uc: f32) -> Result<f32, BsdfSample> {
        if self.opacity >= 1.0 {
            return Ok(uc);
        }
        if uc >= self.opacity {
            return Err(BsdfSample { wi: -wo, weight: Color::ONE, pdf: 0.0, flags: LobeFlags::NULL });
        }
        Ok((uc / self.opacity).min(1.0 - f32::EPSILON / 2.0))
    }

    /// The lobe weights of the camera path (seen from `wo`) restricted to delta (`delta`) or
    /// non-delta lobes, and their sum.
    #[inline(always)]
    fn part_weights(&self, wo: Vec3, delta: bool) -> ([f32; MAX_LOBES], f32) {
        let (mut w, _) = self.selection_weights(&self.lobes.weights, self.lobes.total, self.frame.to_local(wo));
        let mut total = 0.0;
        for (wi, lobe) in w.iter_mut().zip(self.lobes()) {
            if lobe.flags().is_specular() != delta {
                *wi = 0.0;
            }
            total += *wi;
        }
        (w, total)
    }

    /// True when some lobe is diffuse or glossy (and the surface is not fully transparent).
    #[inline]
    pub fn has_smooth(&self) -> bool {
        !self.is_specular_only()
    }

    /// True when some part of the light leaves in a delta direction: a mirror or glass lobe, or
    /// straight through a mask.
    #[inline]
    pub fn has_delta(&self) -> bool {
        self.opacity < 1.0 || self.lobes.flags.is_specular()
    }

    /// True when the non-delta part is glossy only (no diffuse lobe): a rough metal or glass,
    /// which photon mapping follows by ray tracing rather than density estimation.
    #[inline]
    pub fn is_glossy_only(&self) -> bool {
        self.has_smooth() && !self.lobes.flags.is_diffuse()
    }

    /// The share of the non-delta part in the light the surface scatters towards `wo`, by the
    /// lobes' sampling weights (a mask's transparent part counts as delta): the probability with
    /// which a one-sample estimator picks the non-delta part.
    pub fn smooth_fraction(&self, wo: Vec3) -> f32 {
        let (_, smooth) = self.part_weights(wo, false);
        let (_, delta) = self.part_weights(wo, true);
        let s = smooth * self.opacity;
        // Straight through passes all the light: weight 1 against the lobes' albedo weights.
        let d = delta * self.opacity + (1.0 - self.opacity);
        if s + d > 0.0 { s / (s + d) } else { 0.0 }
    }

    /// Samples only the delta part (mirror and glass lobes, and a mask's straight-through part),
    /// weighted so that its mean is the delta part's whole contribution: what a photon-mapping
    /// camera path follows from a surface whose non-delta part it estimates from photons.
    pub fn sample_delta(&self, wo: Vec3, uc: f32, u: Vec2, mode: Transport) -> Option<BsdfSample> {
        let (weights, total) = self.part_weights(wo, true);
        let has_lobes = total > 0.0 && self.opacity > 0.0;
        let p_null = if has_lobes { 1.0 - self.opacity } else { 1.0 };
        if uc < p_null {
            if self.opacity >= 1.0 {
                return None;
            }
            let weight = Color::splat((1.0 - self.opacity) / p_null);
            return Some(BsdfSample { wi: -wo, weight, pdf: 0.0, flags: LobeFlags::NULL });
        }
        let uc = ((uc - p_null) / (1.0 - p_null)).min(1.0 - f32::EPSILON / 2.0);
        let (s, p_lobe) = self.sample_any_lobe(&weights, total, wo, uc, u, mode)?;
        Some(BsdfSample {
            wi: s.wi,
            weight: s.weight * (self.opacity / (p_lobe * (1.0 - p_null))),
            pdf: 0.0,
            flags: s.flags,
        })
    }

    /// Samples only the non-delta part, weighted by its value over its density (final-gather
    /// directions of photon mapping).
    pub fn sample_smooth(&self, wo: Vec3, uc: f32, u: Vec2, mode: Transport) -> Option<BsdfSample> {
        let (weights, total) = self.part_weights(wo, false);
        let (s, _) = self.sample_any_lobe(&weights, total, wo, uc, u, mode)?;
        let (wo_l, wi_l) = (self.frame.to_local(wo), self.frame.to_local(s.wi));
        let kind = if s.wi.dot(self.ng) > 0.0 { LobeFlags::REFLECTION } else { LobeFlags::TRANSMISSION };
        let mut pdf = 0.0;
        for (lobe, w) in self.lobes().iter().zip(&weights) {
            if *w > 0.0 && lobe.flags().intersects(kind) {
                pdf += w / total * lobe.pdf(wo_l, wi_l, mode);
            }
        }
        if !(pdf > 0.0) {
            return None;
        }
        let weight = self.f(wo, s.wi, mode) * (s.wi.dot(self.frame.z).abs() / pdf);
        Some(BsdfSample { wi: s.wi, weight, pdf, flags: s.flags })
    }

    /// The BSDF as one Lambertian lobe, when it is one (unperturbed, lobe weights that do not
    /// depend on `wo`): `eval`, `f`, `pdf`, and for an opaque one `sample` and `sample_lobe`,
    /// without their loop over lobes, frame change and dispatch, the same numbers bit for bit
    /// (`bsdf::tests`). The usual diffuse surface takes this path, and VCM's merges keep it for
    /// every light vertex within the radius.
    #[inline(always)]
    pub fn one_lambert(&self) -> Option<OneLambert> {
        let lobes: &Lobes = &self.lobes;
        let (true, None, Bxdf::Lambert(lobe)) = (lobes.one_lambert, self.perturbed, &lobes.lobes[0]) else {
            return None;
        };
        // `eval` with its one lobe: f = (0 + f_lobe) (opacity x 1), pdf = (0 + (w / w) pdf_lobe) opacity.
        let f = lobe.r * std::f32::consts::FRAC_1_PI * (self.opacity * 1.0);
        Some(OneLambert { n: self.frame.z, ng: self.ng, r: lobe.r, f, opacity: self.opacity })
    }

    /// The albedo of a BSDF made only of Lambertian lobes (its value is that over pi in every
    /// direction), `None` for anything else.
    pub fn lambert_albedo(&self) -> Option<Color> {
        if self.perturbed.is_some() {
            return None;
        }
        let mut sum = Color::ZERO;
        for lobe in self.lobes() {
            sum += lobe.lambert_albedo()?;
        }
        Some(sum * self.opacity)
    }

    /// Samples a direction for a camera path. A non-delta sample is weighted by the whole BSDF
    /// (all non-delta lobes' values over their combined density, as one mixture), a delta sample
    /// by its lobe over the probability of having picked it.
    #[inline]
    pub fn sample(&self, wo: Vec3, uc: f32, u: Vec2, mode: Transport) -> Option<BsdfSample> {
        match self.one_lambert() {
            Some(one) if self.opacity >= 1.0 => self.sample_one_lambert(&one, wo, u),
            _ => self.sample_lobes(wo, uc, u, mode),
        }
    }

    /// `sample_lobes` of a BSDF that is one opaque Lambertian lobe, the same numbers bit for
    /// bit: the cosine-weighted direction in the shading frame, dropped when `wo` is below the
    /// shading normal or the direction below the geometric one.
    #[inline(always)]
    fn sample_one_lambert(&self, one: &OneLambert, wo: Vec3, u: Vec2) -> Option<BsdfSample> {
        if wo.dot(self.frame.z) <= 0.0 {
            return None;
        }
        let wi_l = crate::sampling::warp::cosine_hemisphere(u);
        let pdf = wi_l.z * std::f32::consts::FRAC_1_PI;
        if !(pdf > 0.0) {
            return None;
        }
        let wi = self.frame.to_world(wi_l);
        (wi.dot(self.ng) > 0.0).then_some(BsdfSample { wi, weight: one.r, pdf, flags: LobeFlags::DIFFUSE_REFLECTION })
    }

    /// `sample` lobe by lobe.
    #[inline]
    fn sample_lobes(&self, wo: Vec3, uc: f32, u: Vec2, mode: Transport) -> Option<BsdfSample> {
        let uc = match self.pass_through(wo, uc) {
            Ok(uc) => uc,
            Err(null) => return Some(null),
        };
        let (s, p_lobe) = self.sample_any_lobe(&self.lobes.weights, self.lobes.total, wo, uc, u, mode)?;
        let wi = s.wi;
        if s.flags.is_specular() {
            return Some(BsdfSample { wi, weight: s.weight / p_lobe, pdf: 0.0, flags: s.flags });
        }
        if self.lobes.count == 1 && self.opacity >= 1.0 && self.perturbed.is_none() {
            // One lobe is the whole mixture: its own weight f |cos| / pdf and density are the
            // BSDF's (the contract every lobe's sampler keeps; `bsdf::tests` checks it).
            return (s.pdf > 0.0).then_some(BsdfSample { wi, weight: s.weight, pdf: s.pdf, flags: s.flags });
        }
        let (f, pdf) = self.eval(wo, wi, mode);
        if !(pdf > 0.0) {
            return None;
        }
        let weight = f * (wi.dot(self.frame.z).abs() / pdf);
        Some(BsdfSample { wi, weight, pdf, flags: s.flags })
    }

    /// Samples a direction for a photon: a lobe picked in proportion to its mean albedo,
    /// weighted by that lobe alone (its f |cos| / pdf over the probability of picking it),
    /// which is unbiased too. The weight's mean over the channels is then the BSDF's total mean
    /// albedo, so after Russian roulette on it a photon keeps its power, as Jensen's
    /// lobe-by-albedo roulette keeps it: photons of nearly equal power make the density
    /// estimate quiet, where the mixture weight of `sample` would brighten the photons a sharp
    /// glossy lobe overlapping a diffuse one sends.
    #[inline]
    pub fn sample_lobe(&self, wo: Vec3, uc: f32, u: Vec2, mode: Transport) -> Option<BsdfSample> {
        match self.one_lambert() {
            Some(one) if self.opacity >= 1.0 => {
                // The lobe loop's numbers: its one lobe is picked with probability 1.
                let s = self.sample_one_lambert(&one, wo, u)?;
                let adjoint =
                    if mode == Transport::Importance { self.shading_normal_correction(wo, s.wi) } else { 1.0 };
                Some(BsdfSample { weight: s.weight * adjoint, ..s })
            }
            _ => self.sample_lobe_lobes(wo, uc, u, mode),
        }
    }

    /// `sample_lobe` lobe by lobe.
    #[inline]
    fn sample_lobe_lobes(&self, wo: Vec3, uc: f32, u: Vec2, mode: Transport) -> Option<BsdfSample> {
        let uc = match self.pass_through(wo, uc) {
            Ok(uc) => uc,
            Err(null) => return Some(null),
        };
        let (s, p_lobe) = self.sample_any_lobe(&self.lobes.photon_weights, self.lobes.photon_total, wo, uc, u, mode)?;
        let pdf = if s.flags.is_specular() { 0.0 } else { s.pdf * p_lobe * self.opacity };
        let adjoint = if mode == Transport::Importance { self.shading_normal_correction(wo, s.wi) } else { 1.0 };
        Some(BsdfSample { wi: s.wi, weight: s.weight * (adjoint / p_lobe), pdf, flags: s.flags })
    }

    /// Veach's correction (thesis sec. 5.3) for light carried against a shading normal that is
    /// not the geometric one: importance leaving towards `wi` after arriving from `wo` is
    /// scaled by |wo.ns| |wi.ng| / (|wo.ng| |wi.ns|), so photons on smooth-shaded meshes carry the
    /// power the path tracer sees. 1 where the two normals agree.
    #[inline]
    pub fn shading_normal_correction(&self, wo: Vec3, wi: Vec3) -> f32 {
        let ns = self.frame.z;
        if ns.dot(self.ng).abs() >= 1.0 - 1e-6 {
            return 1.0;
        }
        let num = wo.dot(ns).abs() * wi.dot(self.ng).abs();
        let den = wo.dot(self.ng).abs() * wi.dot(ns).abs();
        if den > 0.0 { num / den } else { 0.0 }
    }
}

mod split;

#[cfg(test)]
mod tests;

#[cfg(test)]
mod microfacet_tests;

#[cfg(test)]
mod principled_tests;
