//! The two random walks of bidirectional methods: a light subpath from `Light::sample_le`
//! through the scene (each vertex with a non-delta part handed to the caller, which connects it
//! to the camera and keeps it), and a camera subpath that at each vertex gathers what the
//! techniques of `strategy` bring: the emitter it hits, a light sample, connections to the
//! light subpath's vertices, and (for vertex merging) whatever the caller's `merge` adds.
//! Both carry their MIS partial sums (`mis::SubpathMis`) along, and in spectral mode the
//! context's wavelengths (`Context::wl`): emission and BSDFs lifted to them, and each its own
//! termination at dispersive glass (`strategy`'s header).
//!
//! A mask's transparent part is not a vertex: a walk that passes straight through keeps its
//! partial sums and measures the next segment from the last real vertex, as shadow rays pass
//! masks by their transmittance. It counts as a delta bounce for the layers, as in the path
//! tracer, but not as a bounce of the depth limit.

use super::mis::SubpathMis;
use super::strategy::{self, CameraVertex, Context, LightVertex};
use crate::camera::Projection;
use crate::film::Layers;
use crate::geometry::{Hit, Ray};
use crate::integrator::layers::LayerPath;
use crate::integrator::lighting::MAX_CROSSINGS;
use crate::material::bsdf::{Bsdf, BsdfSample};
use crate::material::bxdf::Transport;
use crate::math::{Color, Vec3};
use crate::render::RayStats;
use crate::sampling::{Rng32, Sampler};

/// Bounces after which Russian roulette may end a subpath.
const ROULETTE_DEPTH: u32 = 3;

/// Traces a light subpath with numbers from `rng` and calls `vertex` for each vertex with a
/// non-delta part (with its BSDF, the numbers and the ray counts), in order from the light.
/// Vertices up to `ctx.max_depth` bounces are made: the deepest can only be connected to the
/// camera.
pub fn trace_light_path<'a>(
    ctx: &Context<'a>,
    rng: &mut Rng32,
    stats: &mut RayStats,
    mut vertex: impl FnMut(&LightVertex, &Bsdf<'a>, &mut Rng32, &mut RayStats),
) {
    let scene = ctx.scene;
    if ctx.max_depth == 0 {
        return;
    }
    let Some((li, pick_e)) = scene.light_picker.pick(rng.uniform()) else { return };
    let light = &scene.lights[li];
    let Some(e) = light.sample_le(rng.uniform2(), rng.uniform2(), scene.textures()) else { return };
    let mut beta = e.flux / pick_e;
    let mut wl = ctx.wl;
    if wl.is_some() {
        beta = scene.emission_in(beta, li as u32, wl.as_ref());
    }
    if !(beta.max_element() > 0.0) || !beta.is_finite() {
        return;
    }
    let start = beta.max_element();
    let finite = !light.is_infinite();
    let pick_d = scene.direct_picker.prob(li) as f64;
    let emission = (e.pdf_pos * e.pdf_dir) as f64 * pick_e as f64;
    let cos_light = strategy::emission_cos(light, &e.ray, e.n);
    let f = &ctx.factors;
    let mut ray = if finite { e.ray } else { scene.photon_entry(e.ray) };
    // The partial sums after the last scattering, and where it happened (none yet: the light).
    let mut mis = SubpathMis::default();
    let mut last_p = e.ray.o;
    let mut at_light = true;
    let (mut depth, mut bounces, mut delta_only, mut crossings) = (0u32, 0u32, true, 0usize);
    loop {
        stats.rays += 1;
        let Some(hit) = scene.intersect(&ray, f32::INFINITY) else { break };
        let wo = -ray.d;
        let cos_in = wo.dot(hit.ng) as f64;
        let arrived = if at_light {
            // Next-event estimation's density of the light's point is known once the point it
            // would be sampled from is (a sphere light is sampled by the cone it subtends).
            let direct = strategy::start_direct_pdf(light, &e.ray, e.n, hit.p) * pick_d;
            let start = SubpathMis::light_start(direct, emission, cos_light, light.is_delta(), finite, f);
            start.arrive(finite.then(|| (hit.p - last_p).length_squared() as f64), cos_in)
        } else {
            mis.arrive(Some((hit.p - last_p).length_squared() as f64), cos_in)
        };
        let bsdf = scene.bsdf_for(&hit, wo, wl.as_mut(), &mut beta);
        if bsdf.is_black() {
            break;
        }
        depth += 1;
        let hero_only = wl.is_some_and(|wl| wl.secondary_terminated());
        let saturated = bounces.min(u32::from(u16::MAX)) as u16;
        let v =
            LightVertex { hit, wo, beta: beta.into(), mis: arrived, depth, bounces: saturated, delta_only, hero_only };
        if bsdf.has_smooth() {
            vertex(&v, &bsdf, rng, stats);
        }
        if depth >= ctx.max_depth {
            break;
        }
        let Some(s) = bsdf.sample(wo, rng.uniform(), rng.uniform2(), Transport::Importance) else { break };
        bounces += 1;
        if s.flags.is_null() {
            // Straight through a mask: no vertex (see the module header).
            if !cross_mask(&mut depth, &mut crossings) {
                break;
            }
            ray = hit.spawn(ray.d, ctx.ray_bias);
            continue;
        }
        let delta = s.flags.is_specular();
        let (cos, pdf, rev) = scattering(ctx, &hit, &bsdf, wo, &s, Transport::Radiance);
        mis = arrived.scatter(cos, pdf, rev, delta, f.vm_at(false, v.reach()));
        beta *= s.weight * bsdf.shading_normal_correction(wo, s.wi);
        delta_only &= delta;
        if depth >= ROULETTE_DEPTH {
            // Russian roulette on the throughput relative to the light's, as the light tracer.
            let survive = (beta.max_element() / start).min(0.95);
            if !(rng.uniform() < survive) {
                break;
            }
            beta /= survive;
        }
        if !beta.is_finite() || beta == Color::ZERO {
            break;
        }
        last_p = hit.p;
        at_light = false;
        crossings = 0;
        ray = hit.spawn(s.wi, ctx.ray_bias);
    }
}

/// What MIS needs of a walk's scattering at `hit` into `s`: the cosine of the new direction to
/// the geometric normal, the density of the sample and the reverse density, that of the other
/// walk's transport (`reverse`; a delta bounce has none).
#[inline]
fn scattering(ctx: &Context, hit: &Hit, bsdf: &Bsdf, wo: Vec3, s: &BsdfSample, reverse: Transport) -> (f64, f64, f64) {
    let rev = if s.flags.is_specular() {
        0.0
    } else {
        strategy::reverse_pdf(ctx.scene, hit, bsdf, wo, s.wi, reverse, ctx.wl.as_ref())
    };
    (s.wi.dot(hit.ng) as f64, s.pdf as f64, rev as f64)
}

/// A walk straight through a mask's transparent part: the crossing makes no vertex, so it gives
/// back the depth its intersection counted; false (end the walk) once more than `MAX_CROSSINGS`
/// crossings follow one another.
fn cross_mask(depth: &mut u32, crossings: &mut usize) -> bool {
    *depth -= 1;
    *crossings += 1;
    *crossings <= MAX_CROSSINGS
}

/// Most times a camera subpath splits at glass (`Bsdf::dielectric_split`): a split traces the
/// reflection and the refraction both, where a single walk picks one by the Fresnel factor. A
/// small light's highlight on glass (E S L), or seen through a glass ball after one reflection
/// inside it (E S S S L, three splits), is then met by every camera sample that reaches the
/// glass, not by the few that happen to pick reflection; no light subpath can find these paths.
/// Later glass is crossed by the usual choice, so one camera sample costs at most
/// `GLASS_SPLITS + 1` walks. The walks run depth first, the reflection before the refraction;
/// Russian roulette reads a branch's throughput without the split's factor while it stays on
/// mirrors and glass (`Walk::roulette_scale`). Measured on `scenes/16-glossy-caustics.toml`
/// (VCM, 10 s, six seeds; BENCHMARKS.md): RMSE 0.112 without splits, 0.103 with one, 0.101
/// with two, 0.034 with three, 0.033 with six.
pub const GLASS_SPLITS: usize = 3;

/// Where a camera subpath's walk stands between two vertices: what a split at glass keeps of
/// the branch it traces second.
#[derive(Clone, Copy)]
struct Walk {
    ray: Ray,
    beta: Color,
    mis: SubpathMis,
    wl: Option<crate::spectrum::Wavelengths>,
    layer: LayerPath,
    last_p: Vec3,
    first: bool,
    depth: u32,
    /// What Russian roulette multiplies the throughput by before reading it: the inverse of the
    /// split factors (F or 1 - F, and the refraction's 1 / eta^2) the walk took since its last
    /// diffuse or glossy bounce, so that a branch on mirrors and glass is ended as often as
    /// the single walk that picked it by chance would be, not as often as its small weight
    /// says (a branch of weight F = 0.04 would otherwise end 96% of the time from the third
    /// bounce on, and the highlight behind it be a coin toss again).
    roulette_scale: f32,
}

/// Traces the camera subpath of `ray` (its numbers from `sampler`, which made the ray) and
/// returns the light its techniques gather, by layer: emitters it hits, a light sample at each
/// vertex, connections to `light_path` (vertices of one light subpath with their BSDFs in
/// `light_bsdfs`) and what `merge` adds at each vertex with a non-delta part. At glass it may
/// split (`GLASS_SPLITS`), the branches summed; the partial sums of MIS do not read a delta
/// bounce's probability, so each branch weighs its techniques as a single walk would. In
/// spectral mode the light is gathered in the lanes and returned as linear sRGB.
#[allow(clippy::too_many_arguments)]
pub fn trace_camera_path<'a>(
    ctx: &Context<'a>,
    sampler: &mut Sampler,
    ray: Ray,
    light_path: &[LightVertex],
    light_bsdfs: &[Bsdf<'a>],
    stats: &mut RayStats,
    mut merge: impl FnMut(&CameraVertex<'a, '_>, &mut Layers, &mut RayStats),
) -> Layers {
    let scene = ctx.scene;
    let f = &ctx.factors;
    let mut layers = [Color::ZERO; 4];
    let parallel = scene.camera.projection == Projection::Orthographic;
    let mut walk = Walk {
        mis: SubpathMis::camera_start(strategy::camera_start_pdf(ctx, &ray)),
        ray,
        beta: Color::ONE,
        wl: ctx.wl,
        layer: LayerPath::CAMERA,
        last_p: ray.o,
        first: true,
        depth: 0,
        roulette_scale: 1.0,
    };
    // Branches waiting for their turn (each split leaves one), taken last first.
    let mut splits = 0;
    let mut pending: [Option<Walk>; GLASS_SPLITS] = [None; GLASS_SPLITS];
    let mut waiting = 0;
    loop {
        let Walk {
            mut ray,
            mut beta,
            mut mis,
            mut wl,
            mut layer,
            mut last_p,
            mut first,
            mut depth,
            mut roulette_scale,
        } = walk;
        let mut crossings = 0usize;
        loop {
            stats.rays += 1;
            let Some(hit) = scene.intersect(&ray, f32::INFINITY) else {
                if let Some(env) = scene.environment {
                    let le =
                        scene.emission_in(scene.lights[env as usize].environment_radiance(ray.d), env, wl.as_ref());
                    if le != Color::ZERO {
                        let w = if depth == 0 {
                            1.0
                        } else {
                            strategy::environment_weight(ctx, env as usize, last_p, ray.d, &mis, layer)
                        };
                        let c = beta * le * w as f32;
                        layers[layer.emitted()] += c;
                    }
                }
                break;
            };
            let wo = -ray.d;
            let dist2 = (hit.p - last_p).length_squared();
            let parallel_ray = first && parallel;
            let arrived = mis.arrive((!parallel_ray).then_some(dist2 as f64), wo.dot(hit.ng) as f64);
            depth += 1;
            if hit.is_emitter() && hit.is_front(ray.d) {
                let le = scene.emission_in(scene.emitted(&hit, wo), hit.light, wl.as_ref());
                if le != Color::ZERO {
                    // A camera that sees an emitter directly is the only technique for that path.
                    let w = if depth == 1 {
                        1.0
                    } else {
                        strategy::area_light_weight(ctx, &hit, last_p, ray.d, dist2, &arrived, layer)
                    };
                    let c = beta * le * w as f32;
                    layers[layer.emitted()] += c;
                }
            }
            if depth > ctx.max_depth {
                break;
            }
            let bsdf = scene.bsdf_for(&hit, wo, wl.as_mut(), &mut beta);
            if bsdf.has_smooth() {
                let hero_only = wl.is_some_and(|wl| wl.secondary_terminated());
                let x = CameraVertex { hit: &hit, bsdf: &bsdf, wo, beta, mis: arrived, depth, layer, hero_only };
                let (u_pick, u) = (sampler.next_1d(), sampler.next_2d());
                let c = strategy::light_sample(ctx, &x, u_pick, u, stats);
                layers[layer.direct()] += c;
                for (y, y_bsdf) in light_path.iter().zip(light_bsdfs) {
                    // Light vertices come in order of depth: the rest are deeper still.
                    if y.depth + depth > ctx.max_depth {
                        break;
                    }
                    if let Some((c, k)) = strategy::connect(ctx, &x, y, y_bsdf, stats) {
                        layers[k] += c * ctx.connection_scale;
                    }
                }
                merge(&x, &mut layers, stats);
            }
            let (uc, u) = (sampler.next_1d(), sampler.next_2d());
            let split = if splits < GLASS_SPLITS { bsdf.dielectric_split(wo, Transport::Radiance) } else { None };
            let s = match split {
                Some([a, b]) => {
                    // The second branch leaves from here once the first has ended.
                    if let Some(b) = b.filter(|b| b.weight.is_finite() && b.weight != Color::ZERO) {
                        let mut next_layer = layer;
                        next_layer.bounce(true);
                        pending[waiting] = Some(Walk {
                            ray: hit.spawn(b.wi, ctx.ray_bias),
                            beta: beta * b.weight,
                            mis: arrived.scatter_camera(b.wi.dot(hit.ng) as f64, 0.0, 0.0, true, false, f),
                            wl,
                            layer: next_layer,
                            last_p: hit.p,
                            first: false,
                            depth,
                            roulette_scale: roulette_scale / b.weight.max_element(),
                        });
                        waiting += 1;
                    }
                    splits += 1;
                    if let Some(w) = a.map(|a| a.weight.max_element()).filter(|w| *w > 0.0) {
                        roulette_scale /= w;
                    }
                    a
                }
                None => bsdf.sample(wo, uc, u, Transport::Radiance),
            };
            let Some(s) = s else { break };
            if s.flags.is_null() {
                // Straight through a mask: no vertex, a delta bounce for the layers.
                layer.bounce(true);
                if !cross_mask(&mut depth, &mut crossings) {
                    break;
                }
                ray = hit.spawn(ray.d, ctx.ray_bias);
                continue;
            }
            let delta = s.flags.is_specular();
            let (cos, pdf, rev) = scattering(ctx, &hit, &bsdf, wo, &s, Transport::Importance);
            mis = arrived.scatter_camera(cos, pdf, rev, delta, f.merges_at(layer.before_x()), f);
            beta *= s.weight;
            layer.bounce(delta);
            if !delta {
                // Past mirrors and glass the walk is ended by its own throughput again: a split
                // branch that reached a diffuse or glossy surface carries little light on.
                roulette_scale = 1.0;
            }
            if depth >= ROULETTE_DEPTH {
                let survive = (beta.max_element() * roulette_scale).min(0.95);
                if sampler.rng().uniform() >= survive {
                    break;
                }
                beta /= survive;
            }
            if !beta.is_finite() || beta == Color::ZERO {
                break;
            }
            last_p = hit.p;
            first = false;
            crossings = 0;
            ray = hit.spawn(s.wi, ctx.ray_bias);
        }
        let Some(next) = waiting.checked_sub(1).and_then(|k| pending[k].take()) else { break };
        waiting -= 1;
        walk = next;
    }
    ctx.to_film(layers)
}
