//! The camera walk photon mapping and SPPM share (Jensen 2001 sec. 9; pbrt-v4's SPPM visible
//! points): from the camera through mirrors and glass, and through glossy surfaces without a
//! diffuse part (rough metal and glass, followed by ray tracing), to the next surface whose
//! light the integrator estimates from photons. On the way it adds the light emitted at what it
//! meets and, at every surface with a non-delta part, the direct light the integrator's own
//! estimator gives; the layers follow the lobes sampled (`LayerPath`). What happens at the
//! vertex, and whether the path goes on through a delta part there, is the integrator's.
//!
//! Through participating media the walk samples a free flight on each segment
//! (`Medium::sample_distance`, as the volumetric path tracer does): it stops at a scattering
//! point with the probability of a collision there (a `MediumVertex`, whose in-scattered light
//! the integrator estimates), or reaches the surface with its throughput weighted by the
//! transmittance. `null` boundaries are passed without counting as a bounce. In a scene without
//! media none of this runs, and the walk is what it was.
//!
//! A walk made `with_march(n)` marches through homogeneous media instead (Jensen and
//! Christensen 1998's ray marching): each segment through one yields `n` medium vertices, the
//! segment split into `n` strata of equal probability under free-flight sampling restricted to
//! it (by the optical depth of the mean extinction, so a thick medium's points crowd where light
//! still reaches the camera) with one jittered offset for all, each weighted by T / (n pdf);
//! then the walk goes on to the surface with the throughput times the segment's transmittance.
//! Heterogeneous media and segments that never end (into the sky) take a free flight.
//!
//! A walk made `with_wavelengths` is spectral (`crate::spectrum::lanes`): its throughput and the
//! light it adds are per wavelength, the BSDFs it meets are lifted (dispersive glass keeps the
//! hero wavelength alone), and the vertex it stops at carries the lifted BSDF. The integrator's
//! photon estimate there is RGB (photons are stored in RGB): it reads the vertex's RGB BSDF
//! and weights the estimate by `beta_rgb`, the camera path's filter as a colour.

use super::layers::LayerPath;
use super::volpath::TRACKING_STREAM;
use crate::geometry::{Hit, NO_MEDIUM, Ray};
use crate::material::bsdf::{Bsdf, BsdfSample};
use crate::material::bxdf::Transport;
use crate::math::{Color, Vec3};
use crate::medium::{Homogeneous, Medium};
use crate::render::RayStats;
use crate::sampling::{Rng32, Sampler};
use crate::scene::Scene;
use crate::spectrum::Wavelengths;

/// A camera path being walked.
#[derive(Clone, Debug)]
pub struct CameraWalk {
    pub ray: Ray,
    /// The path's throughput so far.
    pub beta: Color,
    pub layer: LayerPath,
    /// A glossy bounce was sampled on the way.
    pub glossy_prefix: bool,
    /// Distance travelled from the camera.
    pub dist: f32,
    /// The last bounce was glossy and its direct light came from a light sample: a light hit now
    /// would count it twice.
    lit_by_light_sample: bool,
    /// Surfaces met so far.
    depth: u32,
    /// Numbers for heterogeneous media's tracking (a side stream of the pixel sample's, made at
    /// the first medium met, so the sampler's dimensions stay where they were).
    tracking: Option<Rng32>,
    /// Medium vertices per segment through a homogeneous medium (0: free flights).
    march_steps: u32,
    /// The segment being marched: the surface at its end, the jittered offset and the next step.
    march: Option<(Hit, f32, u32)>,
    /// The path's wavelengths in spectral mode.
    wl: Option<Wavelengths>,
}

/// Where the walk stopped: a surface, or a scattering point in a medium.
pub enum Stop<'v, 's> {
    Surface(WalkVertex<'v, 's>),
    Medium(MediumVertex),
}

/// A scattering point in a medium the walk stopped at (the walk's throughput does not hold the
/// last segment yet).
#[derive(Clone, Copy, Debug)]
pub struct MediumVertex {
    pub p: Vec3,
    /// Towards the viewer.
    pub wo: Vec3,
    pub medium: u32,
    /// The transmittance over the free-flight density (`MediumSample::tr_over_pdf`): what a
    /// density estimate of the in-scattered light, which holds sigma_s, is multiplied by.
    pub tr_over_pdf: Color,
    /// The same times sigma_s (`MediumSample::weight`): what a light sample is multiplied by.
    pub weight: Color,
    /// Its bounce in the camera path.
    pub bounce: u32,
    /// A ray-marching step: the walk goes on past it (call `next_vertex` again).
    pub marching: bool,
}

/// A surface the walk stopped at, whose light the integrator estimates. Its hit and BSDF stay
/// in the `VertexSlot` the caller gave `next_vertex`: a BSDF holds its lobes (hundreds of
/// bytes), and returning it by value copied it three to five times per camera path (`memcpy`
/// was 4% of SPPM's time); the hit's copies stalled on the stores that had just written it.
pub struct WalkVertex<'v, 's> {
    pub hit: &'v Hit,
    pub bsdf: &'v Bsdf<'s>,
    /// Towards the viewer.
    pub wo: Vec3,
    /// Its bounce in the camera path (1 for the first surface).
    pub bounce: u32,
    /// The depth limit allows no bounce after it.
    pub last: bool,
}

/// Where a camera walk keeps the surface it stopped at (see `WalkVertex`); one per walk, kept
/// by the caller.
#[derive(Default)]
pub struct VertexSlot<'s> {
    hit: Option<Hit>,
    bsdf: Option<Bsdf<'s>>,
}

/// Where `at_surface` stopped: a `WalkVertex` but for its hit and BSDF, which are in the slot.
struct SurfaceStop {
    wo: Vec3,
    bounce: u32,
    last: bool,
}

impl SurfaceStop {
    #[inline(always)]
    fn with<'v, 's>(self, slot: &'v VertexSlot<'s>) -> WalkVertex<'v, 's> {
        let SurfaceStop { wo, bounce, last } = self;
        // `at_surface` put both in the slot before stopping.
        let (Some(hit), Some(bsdf)) = (&slot.hit, &slot.bsdf) else { unreachable!("a surface stop without its hit") };
        WalkVertex { hit, bsdf, wo, bounce, last }
    }
}

impl CameraWalk {
    /// A walk along camera ray `ray` of throughput `beta` (the sample's filter weight).
    pub fn new(ray: Ray, beta: Color) -> Self {
        CameraWalk {
            ray,
            beta,
            layer: LayerPath::CAMERA,
            glossy_prefix: false,
            dist: 0.0,
            lit_by_light_sample: false,
            depth: 0,
            tracking: None,
            march_steps: 0,
            march: None,
            wl: None,
        }
    }

    /// The walk in spectral mode at wavelengths `wl` (see the module docs); `None` keeps RGB.
    #[inline]
    pub fn with_wavelengths(mut self, wl: Option<Wavelengths>) -> Self {
        self.wl = wl;
        self
    }

    /// The path's wavelengths (spectral mode) or `None` (RGB).
    #[inline]
    pub fn wavelengths(&self) -> Option<&Wavelengths> {
        self.wl.as_ref()
    }

    /// The throughput as an RGB colour: itself in RGB mode; in spectral mode the colour of white
    /// (D65) light through it, exact (the lanes' common value) while the throughput is grey.
    #[inline]
    pub fn beta_rgb(&self) -> Color {
        self.rgb_of(self.beta)
    }

    /// A throughput `beta` of the walk's kind as an RGB colour, as `beta_rgb` converts the
    /// walk's own.
    #[inline]
    pub fn rgb_of(&self, beta: Color) -> Color {
        match &self.wl {
            Some(wl) => wl.throughput_to_srgb(beta),
            None => beta,
        }
    }

    /// Spectral light `l` the walk found, as RGB (itself in RGB mode).
    #[inline]
    pub fn to_rgb(&self, l: Color) -> Color {
        match &self.wl {
            Some(wl) => wl.to_srgb(l),
            None => l,
        }
    }

    /// The walk marching through homogeneous media with `steps` vertices per segment (see the
    /// module docs; 0 takes free flights).
    #[inline]
    pub fn with_march(mut self, steps: u32) -> Self {
        self.march_steps = steps;
        self
    }

    /// Step `i` of marching the segment of the current ray through homogeneous medium `m` up to
    /// `t_max`, with offset `u`: the vertex, or `None` past the last step (the throughput then
    /// holds the segment's transmittance).
    fn march_step(&mut self, m: &Homogeneous, t_max: f32, u: f32, i: u32) -> Option<MediumVertex> {
        // At the path's wavelengths in spectral mode.
        let m = &m.at(self.wl.as_ref());
        let n = self.march_steps;
        if i >= n {
            self.beta *= m.transmittance(t_max);
            return None;
        }
        // Free-flight sampling by the mean extinction, restricted to the segment: the strata
        // hold equal probability F(t_max) / n, F(t) = 1 - exp(-sigma t).
        // (Over the four wavelengths in spectral mode, the three channels in RGB.)
        let sigma = match self.wl {
            Some(_) => m.sigma_t.lane_sum(crate::spectrum::LANES) / crate::spectrum::LANES as f32,
            None => m.sigma_t.sum() / 3.0,
        };
        let x = (i as f32 + u) / n as f32;
        let (t, pdf) = if sigma * t_max > 1e-4 {
            let f_max = -(-sigma * t_max).exp_m1();
            let t = (-(-x * f_max).ln_1p() / sigma).min(t_max);
            (t, sigma * (-sigma * t).exp() / f_max)
        } else {
            (x * t_max, 1.0 / t_max)
        };
        let tr_over_pdf = m.transmittance(t) / (n as f32 * pdf);
        let bounce = self.depth + 1;
        Some(MediumVertex {
            p: self.ray.at(t),
            wo: -self.ray.d,
            medium: self.ray.medium,
            tr_over_pdf,
            weight: m.sigma_s() * tr_over_pdf,
            bounce,
            marching: true,
        })
    }

    /// Walks to the next vertex (see the module docs) within `max_depth` bounces, spawning rays
    /// with offset `bias`: light emitted on the way (the environment, emitters) goes to
    /// `add(layer, light)`, and so does `direct(hit, bsdf, wo, medium, sampler, stats)` times
    /// the throughput at every surface with a non-delta part (`medium` the one the walk arrived
    /// in). `None` when the path ends first. The BSDF of each surface met is made in `slot`,
    /// where a surface vertex's stays with its hit.
    #[allow(clippy::too_many_arguments)]
    #[inline]
    pub fn next_vertex<'v, 's>(
        &mut self,
        scene: &'s Scene,
        max_depth: u32,
        bias: f32,
        sampler: &mut Sampler,
        stats: &mut RayStats,
        mut add: impl FnMut(usize, Color),
        mut direct: impl FnMut(&Hit, &Bsdf, Vec3, u32, Option<&Wavelengths>, &mut Sampler, &mut RayStats) -> Color,
        slot: &'v mut VertexSlot<'s>,
    ) -> Option<Stop<'v, 's>> {
        loop {
            if let Some((hit, u, i)) = self.march.take() {
                let Medium::Homogeneous(m) = &scene.media[self.ray.medium as usize] else { unreachable!() };
                if let Some(v) = self.march_step(m, hit.t, u, i) {
                    self.march = Some((hit, u, i + 1));
                    if v.bounce <= max_depth {
                        return Some(Stop::Medium(v));
                    }
                    continue;
                }
                if self.beta == Color::ZERO || !self.beta.is_finite() {
                    return None;
                }
                if let Some(stop) =
                    self.at_surface(scene, &hit, max_depth, bias, sampler, stats, &mut add, &mut direct, slot)
                {
                    return stop.map(|s| Stop::Surface(s.with(slot)));
                }
                continue;
            }
            stats.rays += 1;
            let hit = scene.intersect(&self.ray, f32::INFINITY);
            if self.ray.medium != NO_MEDIUM
                && self.march_steps > 0
                && let (Medium::Homogeneous(_), Some(h)) = (&scene.media[self.ray.medium as usize], &hit)
            {
                self.march = Some((*h, sampler.next_1d(), 0));
                continue;
            }
            if self.ray.medium != NO_MEDIUM {
                let medium = &scene.media[self.ray.medium as usize];
                let t_max = hit.as_ref().map_or(f32::INFINITY, |h| h.t);
                let (u_channel, u) = (sampler.next_1d(), sampler.next_1d());
                let tracking = self.tracking.get_or_insert_with(|| sampler.side_stream(TRACKING_STREAM));
                let ms = medium.sample_distance(&self.ray, t_max, self.beta, u_channel, u, tracking, self.wl.as_ref());
                if ms.scattered {
                    // This scattering event is bounce depth + 1.
                    let depth = self.depth;
                    self.depth += 1;
                    if depth >= max_depth {
                        return None;
                    }
                    let (p, wo, medium) = (self.ray.at(ms.t), -self.ray.d, self.ray.medium);
                    self.dist += ms.t;
                    let (tr_over_pdf, weight) = (ms.tr_over_pdf, ms.weight);
                    let bounce = depth + 1;
                    return Some(Stop::Medium(MediumVertex {
                        p,
                        wo,
                        medium,
                        tr_over_pdf,
                        weight,
                        bounce,
                        marching: false,
                    }));
                }
                self.beta *= ms.weight;
                if self.beta == Color::ZERO || !self.beta.is_finite() {
                    return None;
                }
            }
            // Read where the intersection wrote it (a copy stalled on those stores).
            let Some(hit) = &hit else {
                if !self.lit_by_light_sample {
                    add(self.layer.emitted(), self.beta * scene.environment_in(self.ray.d, self.wl.as_ref()));
                }
                return None;
            };
            if let Some(stop) =
                self.at_surface(scene, hit, max_depth, bias, sampler, stats, &mut add, &mut direct, slot)
            {
                return stop.map(|s| Stop::Surface(s.with(slot)));
            }
        }
    }

    /// The walk at surface `hit`: `Some(stop)` where it stops (or ends, `Some(None)`), `None`
    /// where it goes on (through a boundary, a mirror or glass, or a glossy reflection).
    #[allow(clippy::too_many_arguments)]
    #[inline]
    fn at_surface<'s>(
        &mut self,
        scene: &'s Scene,
        hit: &Hit,
        max_depth: u32,
        bias: f32,
        sampler: &mut Sampler,
        stats: &mut RayStats,
        add: &mut impl FnMut(usize, Color),
        direct: &mut impl FnMut(&Hit, &Bsdf, Vec3, u32, Option<&Wavelengths>, &mut Sampler, &mut RayStats) -> Color,
        slot: &mut VertexSlot<'s>,
    ) -> Option<Option<SurfaceStop>> {
        self.dist += hit.t;
        let wo = -self.ray.d;
        if hit.is_emitter() {
            if hit.is_front(self.ray.d) && !self.lit_by_light_sample {
                let le = scene.emission_in(scene.emitted(hit, wo), hit.light, self.wl.as_ref());
                add(self.layer.emitted(), self.beta * le);
            }
            // A reflecting emitter (one with a BSDF) also reflects.
            if scene.bsdf(hit, wo).is_black() {
                return Some(None);
            }
        }
        let bsdf = &*slot.bsdf.insert(scene.bsdf_for(hit, wo, self.wl.as_mut(), &mut self.beta));
        if scene.has_media() && bsdf.is_invisible() {
            // A medium's boundary: straight on, into the medium beyond, not a bounce.
            self.spawn(scene, hit, self.ray.d, bias);
            return None;
        }
        // This surface is bounce depth + 1: lit only within the depth limit.
        let depth = self.depth;
        self.depth += 1;
        if depth >= max_depth {
            return Some(None);
        }
        let last = depth + 1 >= max_depth;
        if bsdf.is_specular_only() {
            if last {
                return Some(None);
            }
            let Some(s) = bsdf.sample(wo, sampler.next_1d(), sampler.next_2d(), Transport::Radiance) else {
                return Some(None);
            };
            self.follow_delta(scene, hit, &s, bias);
            return None;
        }
        let l = direct(hit, bsdf, wo, self.ray.medium, self.wl.as_ref(), sampler, stats);
        add(self.layer.direct(), self.beta * l);
        if bsdf.is_glossy_only() && !last {
            // Ray-traced glossy reflection: one sampled direction carries the rest.
            let Some(s) = bsdf.sample(wo, sampler.next_1d(), sampler.next_2d(), Transport::Radiance) else {
                return Some(None);
            };
            let delta = s.flags.is_specular();
            self.beta *= s.weight;
            self.layer.bounce(delta);
            self.lit_by_light_sample = !delta;
            self.glossy_prefix |= !delta;
            self.spawn(scene, hit, s.wi, bias);
            return None;
        }
        slot.hit = Some(*hit);
        Some(Some(SurfaceStop { wo, bounce: depth + 1, last }))
    }

    /// The medium the walk is in (`NO_MEDIUM` for vacuum).
    #[inline]
    pub fn medium(&self) -> u32 {
        self.ray.medium
    }

    /// The next ray, from `hit` along `d`, in the medium beyond it.
    #[inline]
    fn spawn(&mut self, scene: &Scene, hit: &Hit, d: Vec3, bias: f32) {
        let medium = scene.medium_after(hit, d, self.ray.medium);
        self.ray = hit.spawn(d, bias);
        self.ray.medium = medium;
    }

    /// Goes on from `hit` through the delta (mirror, glass, straight-through) sample `s`.
    #[inline]
    pub fn follow_delta(&mut self, scene: &Scene, hit: &Hit, s: &BsdfSample, bias: f32) {
        self.beta *= s.weight;
        self.layer.bounce(true);
        self.lit_by_light_sample = false;
        self.spawn(scene, hit, s.wi, bias);
    }
}
