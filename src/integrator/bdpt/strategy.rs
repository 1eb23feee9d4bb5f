//! The techniques that join a camera subpath and a light subpath into a full path, each with its
//! contribution and its multiple importance sampling weight (`mis`): a camera path reaching an
//! emitter (s = 0), next-event estimation (s = 1), a camera vertex connected to a light vertex
//! (s, t >= 2), and a light vertex connected to the camera (t = 1, light tracing's splat).
//! Veach 1997 ch. 10; the weights follow Georgiev's technical report and SmallVCM
//! (`src/vertexcm.hxx`: `GetLightRadiance`, `DirectIllumination`, `ConnectVertices`,
//! `ConnectToCamera`), with lights and cameras asked through caustic's bidirectional
//! interfaces (`Light::sample_le` / `pdf_le`, `Camera::sample_wi` / `pdf_we`).
//!
//! Vertices on a surface have a BSDF seen from the direction they were reached from (`wo`). A
//! light vertex evaluates in importance transport with Veach's shading-normal correction, as the
//! light tracer does; a camera vertex in radiance transport.
//!
//! Spectral mode (`Context::wl`): both subpaths of a full path carry the same wavelengths, one
//! value per lane (`crate::spectrum::lanes`), so every technique that joins them is evaluated at
//! one set of wavelengths. A subpath that crossed a dispersive interface keeps only the hero and
//! holds `terminate_secondary`'s factor in its throughput; a connection or merge of two such
//! subpaths takes the factor once (`spectrum::joined`), so every technique of a full path through
//! dispersive glass estimates the hero alone, times the factor once, and their weights (the
//! densities of BSDFs lifted to the hero's index) sum to one.

use super::mis::{self, MisFactors, Reach, SubpathMis};
use crate::camera::Projection;
use crate::film::Layers;
use crate::geometry::{Hit, Ray};
use crate::integrator::layers::LayerPath;
use crate::integrator::lighting::visibility;
use crate::light::Light;
use crate::material::bsdf::Bsdf;
use crate::material::bxdf::Transport;
use crate::math::{Color, PackedLanes, Vec2, Vec3};
use crate::render::RayStats;
use crate::scene::Scene;
use crate::spectrum::{Wavelengths, joined};

/// What every subpath and technique of one sample index (one VCM iteration) reads.
#[derive(Clone, Copy)]
pub struct Context<'a> {
    pub scene: &'a Scene,
    /// Longest path in bounces (surface vertices between the camera and the light).
    pub max_depth: u32,
    /// The offset rays leave surfaces with (`IntegratorDesc::ray_bias`).
    pub ray_bias: f32,
    pub factors: MisFactors,
    /// Full-film pixels over light paths per sample index: the weight of one light path's
    /// splat (the camera's importance is normalised over the full film, see `camera::importance`).
    pub light_scale: f32,
    /// What a connection to a light subpath's vertex is multiplied by: the inverse of the
    /// probability that the camera path was given a light subpath (VCM's light budget; 1 in
    /// bidirectional path tracing).
    pub connection_scale: f32,
    /// Spectral mode: the wavelengths of the camera sample (bidirectional path tracing) or of
    /// the iteration (VCM) that both subpaths carry, as drawn (neither subpath's termination at
    /// dispersive glass); `None` in RGB mode.
    pub wl: Option<Wavelengths>,
}

impl<'a> Context<'a> {
    /// The context of bidirectional path tracing with `light_paths` light paths per sample
    /// index (one per camera sample of the image).
    pub fn new(scene: &'a Scene, max_depth: u32, ray_bias: f32, light_paths: u64, factors: Option<MisFactors>) -> Self {
        let full = scene.camera.width as f64 * scene.camera.height as f64;
        let scale = full / light_paths.max(1) as f64;
        Context {
            scene,
            max_depth,
            ray_bias,
            factors: factors.unwrap_or(MisFactors::connections_only(scale)),
            light_scale: scale as f32,
            connection_scale: 1.0,
            wl: None,
        }
    }

    /// Light in the lanes of a spectral render as linear sRGB (the film's colours); RGB as it is.
    #[inline]
    pub fn to_film(&self, layers: Layers) -> Layers {
        match &self.wl {
            Some(wl) => layers.map(|c| wl.to_srgb(c)),
            None => layers,
        }
    }

    /// The BSDF of light vertex `y` (as its subpath met it: seen from `y.wo`, lifted in spectral
    /// mode to the wavelengths).
    #[inline]
    pub fn light_bsdf(&self, y: &LightVertex) -> Bsdf<'a> {
        match self.wl {
            // The factor of a dispersive glass is the light path's, already in `y.beta`.
            Some(mut wl) => {
                let mut factor = Color::ONE;
                self.scene.bsdf_for(&y.hit, y.wo, Some(&mut wl), &mut factor)
            }
            None => self.scene.bsdf(&y.hit, y.wo),
        }
    }
}

/// A vertex of a light subpath on a surface with a non-delta part (what connections and merges
/// join); its BSDF is kept beside it (`Bsdf`, seen from `wo`).
#[derive(Clone, Copy, Debug)]
pub struct LightVertex {
    pub hit: Hit,
    /// Towards the previous vertex of the light path: where its light comes from.
    pub wo: Vec3,
    /// Throughput from the light to here: emitted flux over its densities, times each earlier
    /// vertex's BSDF, cosine and correction over its density (not this vertex's BSDF). Packed
    /// (16 bytes aligned to 4) so that the record keeps its RGB-era 160 bytes.
    pub beta: PackedLanes,
    pub mis: SubpathMis,
    /// Surface vertices of the light path up to and including this one (its bounces when it
    /// is connected or merged).
    pub depth: u32,
    /// Scattering events before this vertex, passages through masks included (for the layers),
    /// and whether all were delta (mirrors, glass, straight through).
    /// (Saturating at `u16::MAX`: the layers tell apart only the first few.)
    pub bounces: u16,
    pub delta_only: bool,
    /// Spectral mode: the light path kept only its hero wavelength up to here (`beta` holds
    /// the factor; see the module header). Always false in RGB mode.
    pub hero_only: bool,
}

impl LightVertex {
    /// The layer of this vertex's light reaching the camera through `camera` (the camera path's
    /// layer state at the vertex it is gathered at) after a non-delta bounce at each of the
    /// `joins` vertices where the two subpaths meet (two for a connection, one for a merge or a
    /// connection to the camera, whose state is then `LayerPath::CAMERA`).
    #[inline]
    pub fn layer(&self, camera: LayerPath, joins: u32) -> usize {
        light_layer(u32::from(self.bounces), self.delta_only, camera, joins)
    }

    /// How the light reaching this vertex came, which sets a merge's radius here.
    #[inline]
    pub fn reach(&self) -> Reach {
        Reach::of(self.depth, self.delta_only)
    }
}

/// `LightVertex::layer` of a vertex after `bounces` scattering events, all delta when
/// `delta_only`.
#[inline]
pub fn light_layer(bounces: u32, delta_only: bool, mut camera: LayerPath, joins: u32) -> usize {
    for _ in 0..joins {
        camera.bounce(false);
    }
    // The light path's own bounces come after the joins: only their number and whether all
    // were delta count (`LayerPath` has left its vertex x by then).
    for _ in 0..bounces {
        camera.bounce(delta_only);
    }
    camera.emitted()
}

/// A vertex of a camera subpath, as connections and merges see it.
pub struct CameraVertex<'a, 'b> {
    pub hit: &'b Hit,
    pub bsdf: &'b Bsdf<'a>,
    /// Towards the previous vertex (the camera side).
    pub wo: Vec3,
    /// Throughput from the camera to here (not this vertex's BSDF).
    pub beta: Color,
    pub mis: SubpathMis,
    /// Surface vertices of the camera path up to and including this one.
    pub depth: u32,
    /// The layer state of the camera path here (`integrator::layers`).
    pub layer: LayerPath,
    /// Spectral mode: the camera path kept only its hero wavelength up to here (`beta` holds
    /// the factor). Always false in RGB mode.
    pub hero_only: bool,
}

/// The density with which `hit`, reached from `wi`, samples `wo` (`bsdf` is its BSDF seen from
/// `wo`): the same BSDF's for reflection, the one seen from `wi` across the surface
/// (`Bsdf::pdf_reverse`), lifted in spectral mode (`wl`) as `bsdf` was (a dispersive glass's
/// index at the hero, seen from the other side).
#[inline]
pub fn reverse_pdf(
    scene: &Scene,
    hit: &Hit,
    bsdf: &Bsdf,
    wo: Vec3,
    wi: Vec3,
    mode: Transport,
    wl: Option<&Wavelengths>,
) -> f32 {
    match bsdf.pdf_reverse(wo, wi, mode) {
        Some(p) => p,
        None => match wl {
            Some(wl) => {
                let (mut wl, mut factor) = (*wl, Color::ONE);
                scene.bsdf_for(hit, wi, Some(&mut wl), &mut factor).pdf(wi, wo, mode)
            }
            None => scene.bsdf(hit, wi).pdf(wi, wo, mode),
        },
    }
}

/// The density (position x direction) with which `light` emits `ray` from a point of normal
/// `n`, a delta part counting 1 (`Light::pdf_le` gives a delta part density 0).
#[inline]
pub fn emission_pdf(light: &Light, ray: &Ray, n: Vec3) -> f64 {
    let (pos, dir) = light.pdf_le(ray, n);
    (match light {
        Light::Point { .. } | Light::Spot(_) | Light::Projector(_) => dir,
        Light::Directional { .. } => pos,
        Light::Area { .. } | Light::Environment(_) => pos * dir,
    }) as f64
}

/// The density with which next-event estimation from `p` picks the point a light path started
/// from (ray `ray` leaving a point of normal `n`): per unit area of an area light, per solid
/// angle of an environment, 1 for delta lights. Not times the light's choice probability.
pub fn start_direct_pdf(light: &Light, ray: &Ray, n: Vec3, p: Vec3) -> f64 {
    match light {
        Light::Area { .. } => {
            let v = ray.o - p;
            let d2 = v.length_squared();
            if !(d2 > 0.0) {
                return 0.0;
            }
            let wi = v / d2.sqrt();
            let cos = n.dot(wi).abs();
            light.pdf_li(p, ray.o, n, wi) as f64 * cos as f64 / d2 as f64
        }
        Light::Environment(_) => light.pdf_li(p, p, n, -ray.d) as f64,
        Light::Point { .. } | Light::Spot(_) | Light::Projector(_) | Light::Directional { .. } => 1.0,
    }
}

/// The cosine at a light's own surface for a ray it emits (1 for lights without one).
#[inline]
pub fn emission_cos(light: &Light, ray: &Ray, n: Vec3) -> f64 {
    match light {
        Light::Area { .. } => n.dot(ray.d).abs() as f64,
        Light::Point { .. }
        | Light::Spot(_)
        | Light::Projector(_)
        | Light::Directional { .. }
        | Light::Environment(_) => 1.0,
    }
}

/// A point of a light sampled from a shading point, with what the weights need.
struct DirectSample {
    wi: Vec3,
    dist: f32,
    /// Radiance arriving along `wi` (for delta lights, intensity over the squared distance or
    /// a directional light's irradiance).
    radiance: Color,
    /// Solid-angle density (1 for delta lights).
    pdf: f32,
    /// SmallVCM's direct density: `pdf`, the squared distance for a delta position, 1 for a
    /// directional light.
    mis_direct: f64,
    emission: f64,
    cos_light: f64,
    delta: bool,
}

/// Samples a point of `light` as seen from `p` with the same distribution as `Light::sample`
/// (so `Light::pdf_li` is its density), keeping an area light's normal for the weights.
fn sample_direct(scene: &Scene, light: &Light, p: Vec3, u: Vec2) -> Option<DirectSample> {
    let textures = scene.textures();
    match *light {
        Light::Area { shape, radiance, .. } => {
            let (s, pdf) = shape.sample_towards(p, u)?;
            let v = s.p - p;
            let d2 = v.length_squared();
            if !(d2 > 0.0) || !(pdf > 0.0) {
                return None;
            }
            let dist = d2.sqrt();
            let wi = v / dist;
            let cos_light = s.n.dot(-wi);
            if cos_light <= 0.0 {
                return None;
            }
            let radiance = radiance * light.texture_factor(s.uv, -wi, textures);
            let emission = emission_pdf(light, &Ray::new(s.p, -wi), s.n);
            Some(DirectSample {
                wi,
                dist,
                radiance,
                pdf,
                mis_direct: pdf as f64,
                emission,
                cos_light: cos_light as f64,
                delta: false,
            })
        }
        Light::Environment(_) => {
            let ls = light.sample(p, u, textures)?;
            if !(ls.pdf > 0.0) {
                return None;
            }
            let emission = emission_pdf(light, &Ray::new(p, -ls.wi), -ls.wi);
            Some(DirectSample {
                wi: ls.wi,
                dist: ls.dist,
                radiance: ls.radiance,
                pdf: ls.pdf,
                mis_direct: ls.pdf as f64,
                emission,
                cos_light: 1.0,
                delta: false,
            })
        }
        Light::Point { .. } | Light::Spot(_) | Light::Projector(_) => {
            let ls = light.sample(p, u, textures)?;
            let at = p + ls.wi * ls.dist;
            let emission = emission_pdf(light, &Ray::new(at, -ls.wi), -ls.wi);
            let d2 = ls.dist as f64 * ls.dist as f64;
            Some(DirectSample {
                wi: ls.wi,
                dist: ls.dist,
                radiance: ls.radiance,
                pdf: ls.pdf,
                mis_direct: d2,
                emission,
                cos_light: 1.0,
                delta: true,
            })
        }
        Light::Directional { .. } => {
            let ls = light.sample(p, u, textures)?;
            let emission = emission_pdf(light, &Ray::new(p, -ls.wi), -ls.wi);
            Some(DirectSample {
                wi: ls.wi,
                dist: ls.dist,
                radiance: ls.radiance,
                pdf: ls.pdf,
                mis_direct: 1.0,
                emission,
                cos_light: 1.0,
                delta: true,
            })
        }
    }
}

/// The weight of a camera path (partial sums `mis`, before arriving; layer state `layer`) that
/// leaves the scene along `d` from `from` and sees the environment light `env`.
pub fn environment_weight(ctx: &Context, env: usize, from: Vec3, d: Vec3, mis: &SubpathMis, layer: LayerPath) -> f64 {
    let scene = ctx.scene;
    let light = &scene.lights[env];
    let direct = light.pdf_li(from, from, d, d) as f64 * scene.direct_picker.prob(env) as f64;
    if ctx.factors.direct_by_camera && layer.just_left_x() {
        return mis::direct_emitter_weight(mis, direct);
    }
    let emission = emission_pdf(light, &Ray::new(from, -d), -d) * scene.light_picker.prob(env) as f64;
    mis::emitter_weight(mis, direct, emission, &ctx.factors)
}

/// The weight of a camera path (partial sums `arrived`, after arriving; layer state `layer`)
/// that left `from` along `d` and hit the area light of `hit`, `dist2` away.
pub fn area_light_weight(
    ctx: &Context,
    hit: &Hit,
    from: Vec3,
    d: Vec3,
    dist2: f32,
    arrived: &SubpathMis,
    layer: LayerPath,
) -> f64 {
    let scene = ctx.scene;
    let i = hit.light as usize;
    let light = &scene.lights[i];
    let cos = hit.ng.dot(d).abs() as f64;
    let direct = light.pdf_li(from, hit.p, hit.ng, d) as f64 * cos / (dist2 as f64).max(f64::MIN_POSITIVE);
    let pick_d = scene.direct_picker.prob(i) as f64;
    if ctx.factors.direct_by_camera && layer.just_left_x() {
        return mis::direct_emitter_weight(arrived, direct * pick_d);
    }
    let emission = emission_pdf(light, &Ray::new(hit.p, -d), hit.ng);
    let pick_e = scene.light_picker.prob(i) as f64;
    mis::emitter_weight(arrived, direct * pick_d, emission * pick_e, &ctx.factors)
}

/// Next-event estimation at camera vertex `x` (s = 1): one light chosen by `u_pick`, a point of
/// it by `u`, a shadow ray; the weighted contribution (times `x.beta`) and its layer.
pub fn light_sample(ctx: &Context, x: &CameraVertex, u_pick: f32, u: Vec2, stats: &mut RayStats) -> Color {
    let scene = ctx.scene;
    let Some((li, pick_d)) = scene.direct_picker.pick(u_pick) else { return Color::ZERO };
    let light = &scene.lights[li];
    let Some(ds) = sample_direct(scene, light, x.hit.p, u) else { return Color::ZERO };
    let (f, pdf) = x.bsdf.eval(x.wo, ds.wi, Transport::Radiance);
    if f == Color::ZERO {
        return Color::ZERO;
    }
    let cos = ds.wi.dot(x.bsdf.normal()).abs();
    let radiance = scene.emission_in(ds.radiance, li as u32, ctx.wl.as_ref());
    let contribution = x.beta * f * radiance * (cos / (ds.pdf * pick_d));
    if contribution == Color::ZERO {
        return Color::ZERO;
    }
    let visible = visibility(scene, x.hit.origin(), ds.wi, ds.dist, ctx.ray_bias, stats);
    if !(visible > 0.0) {
        return Color::ZERO;
    }
    let bsdf_pdf = if ds.delta { 0.0 } else { pdf as f64 };
    if ctx.factors.direct_by_camera && x.layer.before_x() {
        let w = mis::direct_light_sample_weight(bsdf_pdf, ds.mis_direct * pick_d as f64);
        return contribution * (visible * w as f32);
    }
    let rev = reverse_pdf(scene, x.hit, x.bsdf, x.wo, ds.wi, Transport::Importance, ctx.wl.as_ref());
    let pick_e = scene.light_picker.prob(li) as f64;
    let w = mis::light_sample_weight(
        &x.mis,
        bsdf_pdf,
        rev as f64,
        ds.mis_direct * pick_d as f64,
        ds.emission * pick_e,
        ds.wi.dot(x.hit.ng) as f64,
        ds.cos_light,
        &ctx.factors,
    );
    contribution * (visible * w as f32)
}

/// Connects camera vertex `x` to light vertex `y` (BSDF `y_bsdf`): the weighted contribution
/// (both throughputs included) and its layer, or `None` when the connection carries nothing.
pub fn connect(
    ctx: &Context,
    x: &CameraVertex,
    y: &LightVertex,
    y_bsdf: &Bsdf,
    stats: &mut RayStats,
) -> Option<(Color, usize)> {
    let scene = ctx.scene;
    let v = y.hit.p - x.hit.p;
    let dist2 = v.length_squared();
    if !(dist2 > 0.0) {
        return None;
    }
    let dist = dist2.sqrt();
    let d = v / dist;
    let (f_x, pdf_x) = x.bsdf.eval(x.wo, d, Transport::Radiance);
    if f_x == Color::ZERO {
        return None;
    }
    let (f_y, pdf_y) = y_bsdf.eval(y.wo, -d, Transport::Importance);
    if f_y == Color::ZERO {
        return None;
    }
    let cos_x = d.dot(x.bsdf.normal()).abs();
    let cos_y = d.dot(y_bsdf.normal()).abs() * y_bsdf.shading_normal_correction(y.wo, -d);
    let contribution = joined(x.beta * f_x * f_y * y.beta.get() * (cos_x * cos_y / dist2), x.hero_only, y.hero_only);
    if contribution == Color::ZERO || !contribution.is_finite() {
        return None;
    }
    let visible = visibility(scene, x.hit.origin(), d, dist, ctx.ray_bias, stats);
    if !(visible > 0.0) {
        return None;
    }
    let (gx, gy) = (d.dot(x.hit.ng).abs() as f64, d.dot(y.hit.ng).abs() as f64);
    let d2 = dist2 as f64;
    let wl = ctx.wl.as_ref();
    let x_rev = reverse_pdf(scene, x.hit, x.bsdf, x.wo, d, Transport::Importance, wl) as f64;
    let y_rev = reverse_pdf(scene, &y.hit, y_bsdf, y.wo, -d, Transport::Radiance, wl) as f64;
    let w = mis::connection_weight(
        x.layer.before_x(),
        y.reach(),
        &x.mis,
        &y.mis,
        pdf_x as f64 * gy / d2,
        x_rev,
        pdf_y as f64 * gx / d2,
        y_rev,
        &ctx.factors,
    );
    Some((contribution * (visible * w as f32), y.layer(x.layer, 2)))
}

/// Connects light vertex `y` (BSDF `bsdf`) to the camera (t = 1) through the lens point `u`
/// picks: where it lands on the film and its weighted contribution by layer (linear sRGB in
/// spectral mode too, ready for the film).
pub fn connect_to_camera(
    ctx: &Context,
    y: &LightVertex,
    bsdf: &Bsdf,
    u: Vec2,
    stats: &mut RayStats,
) -> Option<(Vec2, Layers)> {
    // Direct light is the camera-only techniques' (`MisFactors::direct_by_camera`).
    if ctx.factors.direct_by_camera && y.depth == 1 {
        return None;
    }
    let scene = ctx.scene;
    let cw = scene.camera.sample_wi(y.hit.p, u)?;
    let f = bsdf.f(y.wo, cw.wi, Transport::Importance);
    if f == Color::ZERO || !(cw.pdf > 0.0) {
        return None;
    }
    let cos = cw.wi.dot(bsdf.normal()).abs() * bsdf.shading_normal_correction(y.wo, cw.wi);
    let contribution = y.beta.get() * f * (cos * cw.importance / cw.pdf * ctx.light_scale);
    if contribution == Color::ZERO {
        return None;
    }
    let visible = visibility(scene, y.hit.origin(), cw.wi, cw.dist, ctx.ray_bias, stats);
    if !(visible > 0.0) {
        return None;
    }
    let rev = reverse_pdf(scene, &y.hit, bsdf, y.wo, cw.wi, Transport::Radiance, ctx.wl.as_ref()) as f64;
    // The camera's density of the vertex per unit area: importance over the connection's
    // solid-angle density is pdf_dir / dist^2 for a perspective camera (and the importance
    // itself for an orthographic one, whose direction is a delta).
    let camera_pdf = (cw.importance / cw.pdf) as f64 * cw.wi.dot(y.hit.ng).abs() as f64 * ctx.factors.camera_scale;
    let w = mis::camera_connection_weight(&y.mis, camera_pdf, rev, y.reach(), &ctx.factors);
    let mut layers = [Color::ZERO; 4];
    layers[y.layer(LayerPath::CAMERA, 1)] = contribution * (visible * w as f32);
    Some((cw.raster, ctx.to_film(layers)))
}

/// The density of a camera ray's direction as `mis::SubpathMis::camera_start` takes it: per
/// solid angle for a perspective camera, its importance for an orthographic one (whose first
/// segment then counts no distance), times `camera_scale`; 0 outside the film.
pub fn camera_start_pdf(ctx: &Context, ray: &Ray) -> f64 {
    let cam = &ctx.scene.camera;
    let pdf = match cam.projection {
        Projection::Perspective => cam.pdf_we(ray).1,
        Projection::Orthographic => cam.we(ray).map_or(0.0, |(importance, _)| importance),
    };
    pdf as f64 * ctx.factors.camera_scale
}
