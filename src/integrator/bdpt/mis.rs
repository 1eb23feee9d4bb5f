//! Multiple importance sampling weights of bidirectional path tracing and of vertex connection
//! and merging, computed recursively along each subpath: every vertex carries three partial
//! sums (dVCM, dVC, dVM) from which the weight of any connection or merge made there follows in
//! constant time, whatever the path's length. Sources: Georgiev, Křivánek, Davidovič and
//! Slusallek, "Vertex connection and merging" (SIGGRAPH Asia 2012) and Georgiev's technical
//! report "Implementing vertex connection and merging" (2012), sec. 4-5 (its eq. 31-55), as
//! SmallVCM implements them (`src/vertexcm.hxx`).
//!
//! Conventions (the report's, with the choices caustic makes):
//! - `mis(p)` is the power heuristic's p^2, applied to every density and ratio before they are
//!   multiplied, so products of squares are squares of products. The partial sums are kept in
//!   f64: squared densities of grazing or far-away connections pass 1e38.
//! - Densities include the probability of having chosen the light: light paths choose by power
//!   (`Scene::light_picker`), next-event estimation by `Scene::direct_picker`, so the two
//!   probabilities differ and each appears where its technique does.
//! - Solid angle is turned into area with the cosine to the *geometric* normal (pbrt-v4's
//!   `ConvertDensity`); the throughput keeps the shading normals.
//! - A delta vertex (mirror, glass) makes the density ratio of its two directions 1 (the
//!   report's eq. 53-55): any fixed value used by every technique leaves the weights a
//!   partition of unity.
//! - Russian roulette is left out of the densities (pbrt-v4 does the same): the weights are
//!   still a partition of unity, and the throughput keeps the estimate unbiased.
//! - Camera densities are those of a sample of the whole film (`Camera::pdf_we`, normalised over
//!   the full film) times `camera_scale` = full-film pixels / light paths per sample index:
//!   SmallVCM's pixel-area densities over its light-path count.
//! - Lights at infinity (environment, directional) and an orthographic camera emit parallel
//!   rays: their first segment has no 1 / distance^2 (the report's sec. 5.1).
//! - Direct light, a path light -> x -> camera whose only non-delta vertex is x (the camera side
//!   may pass mirrors and glass), is left to the camera-only techniques when
//!   `MisFactors::direct_by_camera` is set: next-event estimation and the emitter hit by BSDF
//!   sampling share it by the power heuristic as in the path tracer, and light tracing and
//!   merging take none of it. The power heuristic assumes every technique's variance falls as
//!   its density grows; next-event estimation of a point light has no variance to fall, and
//!   near a light the dense light-tracing splats and merges took most of the weight and added
//!   their noise (the bundled caustic box at 10 s: VCM's direct layer noise 0.0069 against
//!   SPPM's 0.0001). Weights that are a partition of unity on every path keep the estimate
//!   unbiased; SPPM and Jensen's photon maps take direct light from next-event estimation too.
//!   (Merges of light straight from the light are no technique anywhere: `Reach::Direct`.)
//! - VCM may trace fewer light paths than camera paths (`vcm::LightBudget`): a fraction rho of
//!   the camera paths then connect to a light path, and there are rho x pixels light paths to
//!   splat and merge. Every technique that uses a light subpath (connections with s >= 2, light
//!   tracing, merges) then has rho times the samples, and the two that do not (a camera path
//!   hitting a light, s = 0, and next-event estimation, s = 1) keep theirs. The partial sums
//!   count techniques relative to a connection, so only the camera-only techniques change: they
//!   weigh `camera_only` = mis(1 / rho) more, which enters at the light subpath's start (its
//!   partial sums there are the s = 1 and s = 0 terms) and, inverted, where a camera-only
//!   technique weighs the others.
//! - A merge's radius depends on how the light reached the vertex (`Reach`), the same rule for
//!   every technique's view of the path: none for light straight from the light (next-event
//!   estimation's, which is noiseless for a point light where a merge is noisy), the narrow
//!   radius for light that came only through mirrors and glass (a caustic, which a wide disc
//!   would blur), and a wide one for light after a diffuse or glossy bounce (smooth, whose
//!   merges within a narrow disc find too few light vertices: SPPM's two discs, issue 32). A
//!   technique's density then carries its own eta = pi r^2 x light paths, and the partial sums
//!   keep every merge term relative to a connection (`d_vc`; the report's dVM is that over the
//!   merge's own eta, no longer one factor). A light walk knows each vertex's reach. A camera
//!   walk counts every merge with the wide radius, right for whatever joins it further on (a
//!   light vertex, a merge or next-event estimation's point scatters off a non-delta surface),
//!   and keeps the latest term apart (`d_last`) for the one path it gets wrong, the one that
//!   ends on a light (`emitter_weight`). The module's test checks all of it against the
//!   definition with three radii in play.
//! - Merges may be left to the camera path's first non-delta vertex alone
//!   (`MisFactors::merge_first_only`, as SPPM gathers only there): a merge at a later camera
//!   vertex then is no technique, the partial sums leave its terms out (`MisFactors::vm_at`
//!   gives 0, `SubpathMis::scatter_camera`'s `merges_here` is false; a light subpath's vertices before its last are never that vertex, and the
//!   last is only for light tracing) and the other techniques share its paths. On the bundled
//!   caustic box the later merges held about half the indirect light with six times the
//!   variance of the first vertex's (BENCHMARKS.md, 12-04): their randomness is the camera's
//!   choice of direction, which more photons do not reduce.

/// The power heuristic's exponent 2.
#[inline(always)]
pub fn mis(p: f64) -> f64 {
    p * p
}

/// Smallest cosine a vertex counts with: a grazing hit would otherwise divide by zero.
const MIN_COS: f64 = 1e-9;

/// The partial weights a subpath carries to its current vertex.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SubpathMis {
    /// Weight of techniques that connect or merge at this vertex's predecessor.
    pub d_vcm: f64,
    /// Of vertex connections and merges further back, relative to a connection here (each
    /// merge with its own radius's `vm`; the report's dVM is this over the merge's).
    pub d_vc: f64,
    /// The part of `d_vc` that is the merge at a camera walk's latest non-delta vertex, per
    /// unit of its `vm`, negative once a delta vertex has followed it (`scatter_camera`; 0
    /// where merging there is no technique, and on light walks).
    pub d_last: f64,
}

/// How the light reaching a vertex came, which sets the radius of a merge there (see the module
/// header). Both walks can tell: a light walk from its own scattering so far, a camera walk
/// from the vertices it meets after the one it merges at (`SubpathMis::scatter_camera`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Reach {
    /// Straight from the light (the light walk's first vertex): no merge, next-event
    /// estimation's light.
    Direct,
    /// Only through mirrors and glass: light that may be focused, merged within the narrow
    /// radius.
    Focused,
    /// After a diffuse or glossy bounce: light that varies slowly, merged within the wide
    /// radius.
    Spread,
}

impl Reach {
    /// Of a light walk's vertex: its surface vertices up to and including it (`depth`, from 1)
    /// and whether every scattering before it was delta.
    #[inline]
    pub fn of(depth: u32, delta_only: bool) -> Reach {
        if depth <= 1 {
            Reach::Direct
        } else if delta_only {
            Reach::Focused
        } else {
            Reach::Spread
        }
    }
}

/// The constants of one iteration that tie connections, merges and the camera together.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MisFactors {
    /// mis(eta) with eta = pi r^2 x light paths: a merge weighed against a connection, with
    /// the narrow radius (`Reach::Focused`; 0 without merging: bidirectional path tracing).
    pub vm: f64,
    /// The same with the wide radius (`Reach::Spread`).
    pub vm_wide: f64,
    /// Full-film pixels over light paths per sample index (see the module header).
    pub camera_scale: f64,
    /// mis(1 / rho): the weight of the camera-only techniques relative to those of a light
    /// subpath, when a fraction rho of camera paths connect to one (1 when all do; see the
    /// module header).
    pub camera_only: f64,
    /// Direct light is the camera-only techniques' alone (see the module header).
    pub direct_by_camera: bool,
    /// Merges only at the camera path's first non-delta vertex (see the module header).
    pub merge_first_only: bool,
}

impl MisFactors {
    /// Bidirectional path tracing: connections only.
    pub fn connections_only(camera_scale: f64) -> Self {
        MisFactors {
            vm: 0.0,
            vm_wide: 0.0,
            camera_scale,
            camera_only: 1.0,
            direct_by_camera: true,
            merge_first_only: false,
        }
    }

    /// Vertex connection and merging with merge radii `radius` and `wide_radius` (module
    /// header) and `light_paths` light paths per iteration (the report's eq. 20 with one
    /// connection and `light_paths` merges).
    pub fn with_merging(radius: f64, wide_radius: f64, light_paths: f64, camera_scale: f64) -> Self {
        let eta = |r: f64| std::f64::consts::PI * r * r * light_paths;
        MisFactors {
            vm: mis(eta(radius)),
            vm_wide: mis(eta(wide_radius)),
            camera_scale,
            camera_only: 1.0,
            direct_by_camera: true,
            merge_first_only: false,
        }
    }

    /// The same when only a fraction `rho` in (0, 1] of the camera paths connect to a light
    /// subpath and there are `rho` times the light paths the factors were made for (module
    /// header). `vm`, `vm_wide` and `camera_scale` stay those of one light path per camera
    /// path: they weigh techniques of light subpaths against each other, whose counts all scale
    /// alike.
    pub fn with_light_fraction(self, rho: f64) -> Self {
        MisFactors { camera_only: mis(1.0 / rho), ..self }
    }

    /// Whether a merge at a vertex is a technique: every non-delta vertex, or under
    /// `merge_first_only` the camera path's first non-delta one (`first`; a light subpath's
    /// vertices before its last never are).
    #[inline]
    pub fn merges_at(&self, first: bool) -> bool {
        !self.merge_first_only || first
    }

    /// `vm` of a merge at a vertex the light reached as `reach` says; 0 where merging is no
    /// technique (`merges_at(first)`, and light straight from the light).
    #[inline]
    pub fn vm_at(&self, first: bool, reach: Reach) -> f64 {
        match reach {
            _ if !self.merges_at(first) => 0.0,
            Reach::Direct => 0.0,
            Reach::Focused => self.vm,
            Reach::Spread => self.vm_wide,
        }
    }
}

impl SubpathMis {
    /// A light path's start (eq. 31-33 before the first segment, with delta lights as in eq.
    /// 48-50). `direct_pdf` is the density with which next-event estimation from the first hit
    /// picks the start (area measure; solid angle for a light at infinity; 1 for a delta light),
    /// `emission_pdf` that of the emitted ray (position x direction, a delta part counting 1),
    /// both times their light's choice probability; `cos` is the cosine at the light's surface.
    pub fn light_start(
        direct_pdf: f64,
        emission_pdf: f64,
        cos: f64,
        delta: bool,
        finite: bool,
        f: &MisFactors,
    ) -> Self {
        if !(emission_pdf > 0.0) {
            return SubpathMis::default();
        }
        // (The terms of the two camera-only techniques, scaled by their relative count.)
        let d_vc = if delta { 0.0 } else { mis(if finite { cos } else { 1.0 } / emission_pdf) * f.camera_only };
        SubpathMis { d_vcm: mis(direct_pdf / emission_pdf) * f.camera_only, d_vc, d_last: 0.0 }
    }

    /// A camera path's start: `pdf` is the density of its first direction (solid angle; for an
    /// orthographic camera the importance, whose first segment then counts no distance), times
    /// `camera_scale`. 0 (a ray no light path could reach) makes the light-tracing technique
    /// count for nothing.
    pub fn camera_start(pdf: f64) -> Self {
        let d_vcm = if pdf > 0.0 { mis(1.0 / pdf) } else { 0.0 };
        SubpathMis { d_vcm, d_vc: 0.0, d_last: 0.0 }
    }

    /// Completes the start or the last scattering at the vertex the path reached, `dist2` away
    /// (`None` for the first segment of parallel rays), arriving at cosine `cos` to its
    /// geometric normal.
    #[inline]
    pub fn arrive(self, dist2: Option<f64>, cos: f64) -> Self {
        let c = mis(cos.abs().max(MIN_COS));
        let d_vcm = match dist2 {
            Some(d2) => self.d_vcm * mis(d2),
            None => self.d_vcm,
        };
        SubpathMis { d_vcm: d_vcm / c, d_vc: self.d_vc / c, d_last: self.d_last / c }
    }

    /// Scattering at the current vertex of a light walk towards a direction at cosine
    /// `cos_out` to its geometric normal, sampled with density `pdf` (solid angle); `pdf_rev` is
    /// the density of the opposite sampling (the arriving direction sampled from the new one).
    /// A delta bounce ignores both densities (see the module header). Eq. 34-36 and 53-55.
    /// `merge_vm` is the `vm` of a merge at the current vertex (`MisFactors::vm_at`; 0 where it
    /// is no technique).
    #[inline]
    pub fn scatter(self, cos_out: f64, pdf: f64, pdf_rev: f64, delta: bool, merge_vm: f64) -> Self {
        let cos_out = cos_out.abs();
        if delta {
            let c = mis(cos_out);
            return SubpathMis { d_vcm: 0.0, d_vc: self.d_vc * c, d_last: self.d_last * c };
        }
        if !(pdf > 0.0) {
            return SubpathMis::default();
        }
        let g = mis(cos_out / pdf);
        let rev = mis(pdf_rev);
        SubpathMis { d_vcm: mis(1.0 / pdf), d_vc: g * (self.d_vc * rev + self.d_vcm + merge_vm), d_last: 0.0 }
    }

    /// `scatter` for a camera walk. A merge's radius at a camera vertex depends on the light
    /// reaching it (`Reach`), which the walk knows only for the paths it continues: whatever
    /// joins it further on (a light vertex, a merge, next-event estimation's point) scatters
    /// off a non-delta surface, so every merge term is counted with the wide radius. A path
    /// that ends on a light instead (s = 0) gives the vertex nearest the light light straight
    /// from it, or focused if mirrors and glass lie between: `d_last` keeps that vertex's term,
    /// negated once a delta vertex follows, for `emitter_weight` to correct.
    #[inline]
    pub fn scatter_camera(
        self,
        cos_out: f64,
        pdf: f64,
        pdf_rev: f64,
        delta: bool,
        merges_here: bool,
        f: &MisFactors,
    ) -> Self {
        if delta {
            let out = self.scatter(cos_out, pdf, pdf_rev, true, 0.0);
            return SubpathMis { d_last: -out.d_last.abs(), ..out };
        }
        let merge_vm = if merges_here { f.vm_wide } else { 0.0 };
        let out = self.scatter(cos_out, pdf, pdf_rev, false, merge_vm);
        let d_last = if merges_here && pdf > 0.0 { mis(cos_out.abs() / pdf) } else { 0.0 };
        SubpathMis { d_last, ..out }
    }
}

/// Weight of a camera path that hit an emitter (after `arrive` for a surface, before it for the
/// environment), the light point having densities `direct_pdf` (next-event estimation from the
/// previous vertex, area measure or solid angle at infinity) and `emission_pdf`, both with their
/// choice probabilities. Eq. 42-43. A camera that sees an emitter directly is not weighted
/// (there is no technique that connects a light point to the camera).
#[inline]
pub fn emitter_weight(cam: &SubpathMis, direct_pdf: f64, emission_pdf: f64, f: &MisFactors) -> f64 {
    // The merge at the vertex nearest the light, which the camera walk counted with the wide
    // radius (`SubpathMis::scatter_camera`): none for light straight from the light, the narrow
    // radius past mirrors and glass.
    let reach = if cam.d_last < 0.0 { f.vm } else { 0.0 };
    let d_vc = (cam.d_vc + cam.d_last.abs() * (reach - f.vm_wide)).max(0.0);
    // Next-event estimation is camera-only as this technique is; the rest use light subpaths.
    let w_camera = mis(direct_pdf) * cam.d_vcm + mis(emission_pdf) * d_vc / f.camera_only;
    1.0 / (1.0 + w_camera)
}

/// `emitter_weight` of a direct path (`MisFactors::direct_by_camera`): next-event estimation
/// from the vertex before is the one other technique.
#[inline]
pub fn direct_emitter_weight(cam: &SubpathMis, direct_pdf: f64) -> f64 {
    1.0 / (1.0 + mis(direct_pdf) * cam.d_vcm)
}

/// `light_sample_weight` of a direct path (`MisFactors::direct_by_camera`): the BSDF sampling
/// the light's direction (`bsdf_pdf`, 0 for a delta light) is the one other technique.
#[inline]
pub fn direct_light_sample_weight(bsdf_pdf: f64, direct_pdf: f64) -> f64 {
    if !(direct_pdf > 0.0) {
        return 0.0;
    }
    1.0 / (1.0 + mis(bsdf_pdf / direct_pdf))
}

/// Weight of next-event estimation at a camera vertex (eq. 44-45). `bsdf_pdf` is the density
/// of the BSDF sampling the light's direction (0 for a delta light), `bsdf_rev_pdf` that of
/// sampling the camera's direction from the light's; `direct_pdf` is the solid-angle density of
/// the light sample (times its choice probability; for a delta-position light its squared
/// distance, for a directional light 1, SmallVCM's conventions), `emission_pdf` the density
/// of the light emitting towards the vertex (times its choice probability), `cos_camera` and
/// `cos_light` the cosines at the vertex (geometric normal) and at the light (1 for lights
/// without a surface).
#[allow(clippy::too_many_arguments)]
#[inline]
pub fn light_sample_weight(
    cam: &SubpathMis,
    bsdf_pdf: f64,
    bsdf_rev_pdf: f64,
    direct_pdf: f64,
    emission_pdf: f64,
    cos_camera: f64,
    cos_light: f64,
    f: &MisFactors,
) -> f64 {
    if !(direct_pdf > 0.0) {
        return 0.0;
    }
    let w_light = mis(bsdf_pdf / direct_pdf);
    let ratio = emission_pdf * cos_camera.abs() / (direct_pdf * cos_light.abs().max(MIN_COS));
    // No merge term: a merge at the vertex would take light straight from the light, which is
    // no technique (`Reach::Direct`).
    let w_camera = mis(ratio) * (cam.d_vcm + cam.d_vc * mis(bsdf_rev_pdf)) / f.camera_only;
    1.0 / (w_light + 1.0 + w_camera)
}

/// Weight of connecting a camera vertex to a light vertex (eq. 40-41). `camera_pdf` is the
/// camera vertex's BSDF density of the connection converted to area at the light vertex,
/// `camera_rev_pdf` (solid angle) its density of the camera path's direction given the
/// connection; `light_pdf` and `light_rev_pdf` the same at the light vertex. `first`: the
/// camera vertex is the camera path's first non-delta one (the light vertex, behind it, is not);
/// `light_reach`: the light reaching the light vertex (`LightVertex::reach`).
#[allow(clippy::too_many_arguments)]
#[inline]
pub fn connection_weight(
    first: bool,
    light_reach: Reach,
    cam: &SubpathMis,
    light: &SubpathMis,
    camera_pdf: f64,
    camera_rev_pdf: f64,
    light_pdf: f64,
    light_rev_pdf: f64,
    f: &MisFactors,
) -> f64 {
    let w_light = mis(camera_pdf) * (f.vm_at(false, light_reach) + light.d_vcm + light.d_vc * mis(light_rev_pdf));
    // The camera vertex's light comes off the light vertex, a non-delta bounce.
    let w_camera = mis(light_pdf) * (f.vm_at(first, Reach::Spread) + cam.d_vcm + cam.d_vc * mis(camera_rev_pdf));
    1.0 / (w_light + 1.0 + w_camera)
}

/// Weight of connecting a light vertex to the camera (light tracing, eq. 46-47): `camera_pdf`
/// is the density with which the camera samples the vertex (area measure, times
/// `camera_scale`), `light_rev_pdf` the vertex's BSDF density of the light path's arriving
/// direction given the camera's; `light_reach` as in `connection_weight`.
#[inline]
pub fn camera_connection_weight(
    light: &SubpathMis,
    camera_pdf: f64,
    light_rev_pdf: f64,
    light_reach: Reach,
    f: &MisFactors,
) -> f64 {
    let w_light = mis(camera_pdf) * (f.vm_at(true, light_reach) + light.d_vcm + light.d_vc * mis(light_rev_pdf));
    1.0 / (w_light + 1.0)
}

/// Weight of merging a camera vertex with a light vertex (eq. 37-39): `camera_pdf` is the
/// camera vertex's BSDF density of the light's arriving direction, `camera_rev_pdf` of the
/// camera path's direction given the light's; `vm` that of the merge's radius
/// (`MisFactors::vm_at` of the light vertex's `Reach`).
#[inline]
pub fn merge_weight(cam: &SubpathMis, light: &SubpathMis, camera_pdf: f64, camera_rev_pdf: f64, vm: f64) -> f64 {
    let others = light.d_vcm + light.d_vc * mis(camera_pdf) + cam.d_vcm + cam.d_vc * mis(camera_rev_pdf);
    1.0 / (1.0 + others / vm)
}

#[cfg(test)]
mod tests {
    //! The recursion against the definition: on abstract paths (random densities, cosines and
    //! distances), every technique's weight computed from the subpaths' partial sums must equal
    //! its density's square over the sum of all techniques' squared densities, so the weights of
    //! each path add up to 1.

    use super::*;
    use crate::sampling::Rng32;

    #[derive(Clone, Copy, Debug, PartialEq)]
    enum LightKind {
        Area,
        Point,
        Environment,
        Directional,
    }

    /// A path v0 (on the light) .. v_n (the camera) with every density the techniques use.
    struct Path {
        n: usize,
        light: LightKind,
        orthographic: bool,
        /// cos at v_i of the edge to v_(i-1) and to v_(i+1) (geometric normal).
        cos_prev: Vec<f64>,
        cos_next: Vec<f64>,
        /// Squared length of edge v_i v_(i+1).
        d2: Vec<f64>,
        /// BSDF density at v_i of the direction to v_(i+1) given v_(i-1) (the light path's
        /// sampling), and of v_(i-1) given v_(i+1) (the camera path's).
        to_next: Vec<f64>,
        to_prev: Vec<f64>,
        delta: Vec<bool>,
        pick_e: f64,
        pick_d: f64,
        /// Emission: position density (area, or the disk's for lights at infinity) and
        /// direction density (solid angle); next-event density of v0 from v1 (solid angle).
        pdf_pos: f64,
        pdf_dir: f64,
        direct_w: f64,
        /// The camera's density of its direction to v_(n-1) (importance for orthographic),
        /// times the camera scale.
        camera: f64,
        /// pi r^2 light paths, or None without merging.
        eta: Option<f64>,
        /// The same with the wide radius (module header).
        eta_wide: f64,
        /// The fraction of camera paths that connect to a light subpath (and of light paths).
        rho: f64,
        /// `MisFactors::direct_by_camera`.
        direct_by_camera: bool,
        /// `MisFactors::merge_first_only`.
        merge_first_only: bool,
    }

    impl Path {
        fn random(rng: &mut Rng32, n: usize, light: LightKind, orthographic: bool, eta: Option<f64>) -> Path {
            let mut r = |lo: f64, hi: f64| lo + (hi - lo) * rng.uniform() as f64;
            let mut p = Path {
                n,
                light,
                orthographic,
                cos_prev: vec![0.0; n + 1],
                cos_next: vec![0.0; n + 1],
                d2: vec![0.0; n + 1],
                to_next: vec![0.0; n + 1],
                to_prev: vec![0.0; n + 1],
                delta: vec![false; n + 1],
                pick_e: r(0.1, 1.0),
                pick_d: r(0.1, 1.0),
                pdf_pos: r(0.1, 3.0),
                pdf_dir: r(0.05, 2.0),
                direct_w: r(0.1, 5.0),
                camera: r(0.1, 20.0),
                eta,
                eta_wide: eta.unwrap_or(0.0),
                rho: 1.0,
                direct_by_camera: false,
                merge_first_only: false,
            };
            for i in 0..=n {
                p.cos_prev[i] = r(0.05, 1.0);
                p.cos_next[i] = r(0.05, 1.0);
                p.d2[i] = r(0.1, 10.0);
                p.to_next[i] = r(0.05, 3.0);
                p.to_prev[i] = r(0.05, 3.0);
            }
            // Some surface vertices are mirrors: one density both ways (see the module header).
            for i in 1..n {
                if r(0.0, 1.0) < 0.3 {
                    p.delta[i] = true;
                    p.to_prev[i] = p.to_next[i];
                }
            }
            p
        }

        fn factors(&self) -> MisFactors {
            let f = match self.eta {
                Some(eta) => MisFactors {
                    vm: mis(eta),
                    vm_wide: mis(self.eta_wide),
                    camera_scale: 1.0,
                    camera_only: 1.0,
                    direct_by_camera: true,
                    merge_first_only: true,
                },
                None => MisFactors::connections_only(1.0),
            };
            let merge_first_only = self.merge_first_only && self.eta.is_some();
            let f = MisFactors { direct_by_camera: self.direct_by_camera, merge_first_only, ..f };
            f.with_light_fraction(self.rho)
        }

        fn finite_light(&self) -> bool {
            matches!(self.light, LightKind::Area | LightKind::Point)
        }

        fn delta_light(&self) -> bool {
            matches!(self.light, LightKind::Point | LightKind::Directional)
        }

        /// Area density of v_i sampled from v_(i-1) by the light path.
        fn fwd(&self, i: usize) -> f64 {
            if i == 0 {
                // Position: the choice of the light times its position density (1 for a point;
                // a direction for lights at infinity, whose own density is counted at v1).
                return self.pick_e
                    * match self.light {
                        LightKind::Area => self.pdf_pos,
                        LightKind::Point => 1.0,
                        LightKind::Environment => self.pdf_dir,
                        LightKind::Directional => 1.0,
                    };
            }
            let pdf_w = if i == 1 {
                match self.light {
                    LightKind::Area | LightKind::Point => self.pdf_dir,
                    // Parallel rays: the disk's area density, projected.
                    LightKind::Environment | LightKind::Directional => self.pdf_pos,
                }
            } else {
                self.to_next[i - 1]
            };
            let g = if i == 1 && !self.finite_light() { 1.0 } else { 1.0 / self.d2[i - 1] };
            pdf_w * self.cos_prev[i] * g
        }

        /// Area density of v_i sampled from v_(i+1) by the camera path (v0 by the BSDF).
        fn rev(&self, i: usize) -> f64 {
            if i == self.n - 1 {
                let g = if self.orthographic { 1.0 } else { 1.0 / self.d2[i] };
                return self.camera * self.cos_next[i] * g;
            }
            if i == 0 && !self.finite_light() {
                return self.to_prev[1];
            }
            self.to_prev[i + 1] * self.cos_next[i] / self.d2[i]
        }

        /// Next-event estimation's density of v0 (area, or solid angle at infinity).
        fn direct(&self) -> f64 {
            self.pick_d
                * match self.light {
                    LightKind::Area => self.direct_w * self.cos_next[0] / self.d2[0],
                    LightKind::Environment => self.direct_w,
                    LightKind::Point | LightKind::Directional => 1.0,
                }
        }

        /// The density of technique `s` (light vertices v0 .. v_(s-1), camera vertices v_s ..
        /// v_n), or None where it cannot make the path.
        fn connection(&self, s: usize) -> Option<f64> {
            let n = self.n;
            if s == 0 && self.delta_light() {
                return None;
            }
            // The two vertices joined must not be delta (v0 and the camera never are).
            if (s >= 2 && self.delta[s - 1]) || (s >= 1 && s < n && self.delta[s]) {
                return None;
            }
            // With s = 1, v0 comes from next-event estimation instead of the light path.
            let mut p = if s == 1 { self.direct() } else { 1.0 };
            for i in 0..s {
                if !(s == 1 && i == 0) {
                    p *= self.fwd(i);
                }
            }
            for i in s..n {
                p *= self.rev(i);
            }
            // Techniques of a light subpath have rho times the samples.
            Some(if s >= 2 { p * self.rho } else { p })
        }

        /// The path's first non-delta vertex seen from the camera (v_(n-1) is the first the
        /// camera path reaches).
        fn first_from_camera(&self) -> Option<usize> {
            (1..self.n).rev().find(|&i| !self.delta[i])
        }

        /// How the light reaches v_i (`Reach`).
        fn reach(&self, i: usize) -> Reach {
            Reach::of(i as u32, (1..i).all(|j| self.delta[j]))
        }

        /// Whether a merge at v_i is a technique (`MisFactors::merges_at`).
        fn merges_at(&self, i: usize) -> bool {
            !self.merge_first_only || self.first_from_camera() == Some(i)
        }

        /// The density of merging at surface vertex i (light path to v_i, camera path to v_i).
        fn merge(&self, i: usize) -> Option<f64> {
            let eta = self.eta?;
            if self.delta[i] || !self.merges_at(i) {
                return None;
            }
            let eta = match self.reach(i) {
                Reach::Direct => return None,
                Reach::Focused => eta,
                Reach::Spread => self.eta_wide,
            };
            let mut p = eta * self.rho;
            for j in 0..=i {
                p *= self.fwd(j);
            }
            for j in i..self.n {
                p *= self.rev(j);
            }
            Some(p)
        }

        fn light_subpath(&self, s: usize) -> SubpathMis {
            let f = self.factors();
            let emission = self.pick_e
                * match self.light {
                    LightKind::Point => self.pdf_dir,
                    LightKind::Directional => self.pdf_pos,
                    LightKind::Area | LightKind::Environment => self.pdf_pos * self.pdf_dir,
                };
            let direct = self.direct();
            let mut m = SubpathMis::light_start(
                direct,
                emission,
                self.cos_next[0],
                self.delta_light(),
                self.finite_light(),
                &f,
            );
            m = m.arrive(self.finite_light().then_some(self.d2[0]), self.cos_prev[1]);
            for i in 1..s - 1 {
                m = m.scatter(
                    self.cos_next[i],
                    self.to_next[i],
                    self.to_prev[i],
                    self.delta[i],
                    f.vm_at(false, self.reach(i)),
                );
                m = m.arrive(Some(self.d2[i]), self.cos_prev[i + 1]);
            }
            m
        }

        /// The camera path's partial sums at v_i (before arriving there when `arrive` is false).
        fn camera_subpath(&self, i: usize, arrive: bool) -> SubpathMis {
            let f = self.factors();
            let n = self.n;
            let mut m = SubpathMis::camera_start(self.camera);
            let first = if self.orthographic { None } else { Some(self.d2[n - 1]) };
            m = m.arrive(first, self.cos_next[n - 1]);
            for j in (i + 1..n).rev() {
                m = m.scatter_camera(
                    self.cos_prev[j],
                    self.to_prev[j],
                    self.to_next[j],
                    self.delta[j],
                    self.merges_at(j),
                    &f,
                );
                if j - 1 > i || arrive {
                    m = m.arrive(Some(self.d2[j - 1]), self.cos_next[j - 1]);
                }
            }
            m
        }

        /// Whether the path is direct light (its only non-delta vertex is v1) that
        /// `MisFactors::direct_by_camera` leaves to the camera-only techniques.
        fn direct_by_camera(&self) -> bool {
            self.direct_by_camera && !self.delta[1] && (2..self.n).all(|i| self.delta[i])
        }

        /// The weight the definition gives each technique: its density's square over the sum of
        /// those of every technique that may make the path (only the camera-only ones, s = 0
        /// and s = 1, for direct light under `direct_by_camera`).
        fn expected_weights(&self, t: &[(String, f64, f64)]) -> Vec<f64> {
            let counts = |name: &str| !self.direct_by_camera() || name == "s=0" || name == "s=1";
            let total: f64 = t.iter().filter(|(name, _, _)| counts(name)).map(|(_, p, _)| mis(*p)).sum();
            t.iter().map(|(name, p, _)| if counts(name) { mis(*p) / total } else { 0.0 }).collect()
        }

        /// (the technique's density, the weight the recursion gives it) for every technique.
        fn techniques(&self) -> Vec<(String, f64, f64)> {
            let f = self.factors();
            let n = self.n;
            let direct = self.direct_by_camera();
            let mut out = Vec::new();
            for s in 0..=n {
                let Some(p) = self.connection(s) else { continue };
                let w = if s == 0 && direct {
                    let cam = self.camera_subpath(0, self.finite_light());
                    direct_emitter_weight(&cam, self.direct())
                } else if s == 1 && direct {
                    let bsdf = if self.delta_light() { 0.0 } else { self.to_prev[1] };
                    let direct_w = match self.light {
                        LightKind::Area | LightKind::Environment => self.direct_w,
                        LightKind::Point => self.d2[0],
                        LightKind::Directional => 1.0,
                    };
                    direct_light_sample_weight(bsdf, direct_w * self.pick_d)
                } else if s == n && direct {
                    // Light tracing from v1 (the code's light vertex of depth 1) takes none.
                    0.0
                } else if s == 0 {
                    // The camera path hits the light.
                    let emission = self.pick_e * self.pdf_pos * self.pdf_dir;
                    let direct = self.direct();
                    let cam = self.camera_subpath(0, self.finite_light());
                    emitter_weight(&cam, direct, emission, &f)
                } else if s == 1 {
                    let cam = self.camera_subpath(1, true);
                    let (direct_w, emission, cos_light) = match self.light {
                        LightKind::Area => (self.direct_w, self.pdf_pos * self.pdf_dir, self.cos_next[0]),
                        LightKind::Point => (self.d2[0], self.pdf_dir, 1.0),
                        LightKind::Environment => (self.direct_w, self.pdf_pos * self.pdf_dir, 1.0),
                        LightKind::Directional => (1.0, self.pdf_pos, 1.0),
                    };
                    let bsdf = if self.delta_light() { 0.0 } else { self.to_prev[1] };
                    light_sample_weight(
                        &cam,
                        bsdf,
                        self.to_next[1],
                        direct_w * self.pick_d,
                        emission * self.pick_e,
                        self.cos_prev[1],
                        cos_light,
                        &f,
                    )
                } else if s == n {
                    let light = self.light_subpath(n);
                    let g = if self.orthographic { 1.0 } else { 1.0 / self.d2[n - 1] };
                    camera_connection_weight(
                        &light,
                        self.camera * self.cos_next[n - 1] * g,
                        self.to_prev[n - 1],
                        self.reach(n - 1),
                        &f,
                    )
                } else {
                    let (y, x) = (s - 1, s);
                    let light = self.light_subpath(s);
                    let cam = self.camera_subpath(x, true);
                    connection_weight(
                        self.first_from_camera() == Some(x),
                        self.reach(y),
                        &cam,
                        &light,
                        self.to_prev[x] * self.cos_next[y] / self.d2[y],
                        self.to_next[x],
                        self.to_next[y] * self.cos_prev[x] / self.d2[y],
                        self.to_prev[y],
                        &f,
                    )
                };
                out.push((format!("s={s}"), p, w));
            }
            for i in 1..n {
                let Some(p) = self.merge(i) else { continue };
                let light = self.light_subpath(i + 1);
                let cam = self.camera_subpath(i, true);
                // A merge at v1 of a direct path (light vertex of depth 1) takes none.
                // (`merge` made it only where merging at v_i is a technique.)
                let vm = f.vm_at(true, self.reach(i));
                let w = if direct { 0.0 } else { merge_weight(&cam, &light, self.to_prev[i], self.to_next[i], vm) };
                out.push((format!("merge at v{i}"), p, w));
            }
            out
        }
    }

    #[test]
    fn recursive_weights_are_the_power_heuristic_over_every_technique() {
        let mut rng = Rng32::new(17);
        let kinds = [LightKind::Area, LightKind::Point, LightKind::Environment, LightKind::Directional];
        let mut checked = 0;
        for trial in 0..400 {
            let n = 2 + trial % 6;
            let light = kinds[trial / 6 % 4];
            let orthographic = trial % 5 == 0;
            let eta = (trial % 3 == 0).then(|| 0.01 + rng.uniform() as f64);
            let mut path = Path::random(&mut rng, n, light, orthographic, eta);
            // A wide radius for merges after a non-delta bounce in two trials of three with
            // merging (the same radius in the third).
            if let Some(eta) = eta {
                path.eta_wide = eta * [1.0, 4.0, 1.0 + 15.0 * rng.uniform() as f64][trial % 9 / 3];
            }
            // Fewer light paths than camera paths in half the trials (with and without merging).
            path.rho = [1.0, 0.25, 1.0 / 16.0, 1.0][trial % 4];
            // Direct light left to the camera-only techniques in the odd trials (every light kind
            // and path length meets both).
            path.direct_by_camera = trial % 2 == 1;
            // Merges at the camera path's first non-delta vertex only, in half the trials with
            // merging (trials of both parities of the rule above).
            path.merge_first_only = trial % 7 < 4;
            let t = path.techniques();
            let expected = path.expected_weights(&t);
            let sum: f64 = t.iter().map(|(_, _, w)| w).sum();
            for ((name, _, w), &expected) in t.iter().zip(&expected) {
                assert!(
                    (w - expected).abs() < 1e-9 * (1.0 + expected),
                    "{light:?} n={n} ortho={orthographic} eta={eta:?}: {name} weight {w} vs {expected} ({t:?})"
                );
            }
            assert!(t.is_empty() || (sum - 1.0).abs() < 1e-9, "{light:?} n={n}: weights sum to {sum}");
            checked += t.len();
        }
        assert!(checked > 1200, "only {checked} techniques checked");
    }
}
