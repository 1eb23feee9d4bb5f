//! Photon tracing (Jensen 2001 sec. 2): photons leave the lights, carrying flux, and scatter
//! through the scene by Russian roulette; those landing on diffuse surfaces are recorded.
//!
//! Two passes fill the two maps:
//! - global: photons emitted from every light by its emission distribution; every hit on a
//!   surface with a diffuse or glossy lobe is stored (also the first, flagged `DIRECT`, and the
//!   ones that came only through mirrors and glass, flagged `CAUSTIC`, so each use of the map can
//!   pick what it needs); passing straight through a mask's transparent part is not a bounce;
//! - caustic: photons aimed at the bounding spheres of mirror and glass objects (the projection
//!   map of Jensen 1996, with the density of the aimed directions in the photon's weight), kept
//!   only for L S+ D paths, emitted in batches until enough are stored or a cap is reached.
//!
//! Photon `i` of a pass draws its random numbers from a stream seeded by (seed, pass, i), and
//! photons are traced in fixed chunks whose hits are read in chunk order (`PhotonHits`), so
//! the maps are the same for any thread count.

use super::hits::PhotonHits;
use crate::geometry::Ray;
use crate::light::Light;
use crate::material::bsdf::Bsdf;
use crate::material::bxdf::Transport;
use crate::math::{Color, Frame, PackedColor, Vec2, Vec3};
use crate::progress::Progress;
use crate::sampling::warp::{concentric_disk, uniform_cone};
use crate::sampling::{Rng32, SeedPrefix};
use crate::scene::Scene;
use crate::spectrum::Wavelengths;
use rayon::prelude::*;
use std::f32::consts::PI;
use std::sync::atomic::{AtomicBool, Ordering};

/// Flag: the photon's first bounce (L D): light a direct-lighting computation already counts.
pub const DIRECT: u8 = 1;
/// Flag: the photon came from the light only through specular bounces (L S+ D).
pub const CAUSTIC: u8 = 2;
/// Flag: a scattering event in a participating medium (`Store::Media` only; never in a packed
/// photon map).
pub const VOLUME: u8 = 4;
/// Flag: the photon came from the light through specular or glossy bounces only, none diffuse
/// and none in a medium (a superset of `CAUSTIC`): light that may still be focused, which SPPM
/// keeps in its pixels' narrow disc (`integrator::sppm`). Never in a packed photon map.
pub const FOCUSED: u8 = 8;

/// Photon depths are stored up to this (a photon scatters at most `MAX_BOUNCES` times, and a
/// map keeps six bits of it).
pub const MAX_PHOTON_DEPTH: u32 = MAX_BOUNCES - 1;
const _: () = assert!(MAX_PHOTON_DEPTH < 64);

/// The most scattering events a photon may have had before arriving at a surface that is
/// bounce `bounce` of a camera path, so that the whole path has at most `max_depth` bounces
/// (the path tracer's limit); `None` when no photon's light may count there. Photon depths
/// are all within `MAX_PHOTON_DEPTH`, so a larger result filters nothing.
#[inline]
pub fn photon_depth_limit(max_depth: u32, bounce: u32) -> Option<u32> {
    max_depth.checked_sub(bounce).map(|d| d.min(MAX_PHOTON_DEPTH))
}

/// A photon map's flags byte: the flags in the low two bits, the depth in the other six.
#[inline]
pub fn packed_flags(h: &PhotonHit) -> u8 {
    (h.flags & (DIRECT | CAUSTIC)) | h.depth << 2
}

/// The depth stored in a photon map's flags byte (`packed_flags`).
#[inline]
pub fn packed_depth(flags: u8) -> u32 {
    u32::from(flags >> 2)
}

/// A photon hit before packing: where, travelling which way, with what flux (watts).
#[derive(Clone, Copy, Debug)]
pub struct PhotonHit {
    pub p: Vec3,
    /// Direction of travel (towards the surface).
    pub dir: Vec3,
    /// RGB (or CIE XYZ) in either mode.
    pub flux: PackedColor,
    pub flags: u8,
    /// Scattering events before this hit (0: straight from the light).
    pub depth: u8,
    /// Surface normal at the hit, on the side the photon arrived from.
    pub n: Vec3,
}

/// What one pass produced.
#[derive(Clone, Debug, Default)]
pub struct PhotonPass {
    /// Stored hits, flux already divided by the number emitted.
    pub hits: PhotonHits,
    pub emitted: u64,
    /// The caustic pass stopped at its emission cap before storing the requested number.
    pub capped: bool,
    /// The pass was stopped by the cancel flag: its photons are incomplete.
    pub cancelled: bool,
}

/// What a long computation watches while it runs: a cancel flag (Ctrl-C) it checks between
/// chunks of work, and optionally a progress display it advances.
#[derive(Clone, Copy)]
pub struct Watch<'a> {
    pub cancel: &'a AtomicBool,
    pub progress: Option<&'a Progress>,
}

impl<'a> Watch<'a> {
    /// Nothing to watch: never cancelled, no progress.
    pub fn none() -> Watch<'static> {
        static NEVER: AtomicBool = AtomicBool::new(false);
        Watch { cancel: &NEVER, progress: None }
    }

    #[inline]
    pub fn cancelled(&self) -> bool {
        self.cancel.load(Ordering::Relaxed)
    }

    #[inline]
    pub fn advance(&self, n: u64) {
        if let Some(p) = self.progress {
            p.inc(n);
        }
    }
}

/// Which hits a photon pass stores.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Store {
    /// Every hit on a surface with a non-delta part (the global photon map).
    All,
    /// Every such hit but the photons' first (SPPM, which samples direct light from the lights).
    Indirect,
    /// Hits after mirrors and glass only, and no further bounce (the caustic map).
    Caustic,
    /// `Indirect`, and every scattering event in a medium, the first included (flagged
    /// `VOLUME`): SPPM in a scene with media, whose in-scattered light comes from them.
    Media,
    /// `All`, and every scattering event in a medium, the first included (flagged `VOLUME`):
    /// the photon integrator's global and volume maps in a scene with media.
    Volume,
}

/// How a pass's photons carry colour: RGB, or (spectral mode) wavelengths of their own, stored
/// converted to linear sRGB (which may be negative in a channel: SPPM's hits are floats) or to
/// CIE XYZ (never negative: the packed powers of a photon map).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PhotonColour {
    Rgb,
    SpectralSrgb,
    SpectralXyz,
}

/// The `PhotonColour` of a pass: RGB unless `spectral`, then XYZ when `xyz`.
pub fn spectral_store(spectral: bool, xyz: bool) -> PhotonColour {
    match (spectral, xyz) {
        (false, _) => PhotonColour::Rgb,
        (true, false) => PhotonColour::SpectralSrgb,
        (true, true) => PhotonColour::SpectralXyz,
    }
}

const CHUNK: u64 = 4096;
/// Bounces after which a photon is dropped (Russian roulette ends nearly all paths long before).
pub const MAX_BOUNCES: u32 = 64;

/// Traces `n_emit` photons from the scene's lights (chosen in proportion to power); rays leave
/// surfaces with offset `bias`.
pub fn trace_global(scene: &Scene, n_emit: u64, seed: u64, bias: f32, watch: Watch) -> PhotonPass {
    let mut hits = PhotonHits::default();
    trace_global_into(scene, n_emit, seed, bias, Store::All, PhotonColour::Rgb, watch, &mut hits);
    PhotonPass { hits, emitted: n_emit, capped: false, cancelled: watch.cancelled() }
}

/// `trace_global` storing the hits `store` names into `hits` (its old contents replaced, its
/// buffer kept: SPPM traces a pass per iteration into the same one). In spectral mode
/// (`colour`), each photon samples wavelengths of its own (`crate::spectrum::lanes`) and is
/// stored with its power converted as `colour` says.
#[allow(clippy::too_many_arguments)]
pub fn trace_global_into(
    scene: &Scene,
    n_emit: u64,
    seed: u64,
    bias: f32,
    store: Store,
    colour: PhotonColour,
    watch: Watch,
    hits: &mut PhotonHits,
) {
    // Every photon's stream is hash_seed(&[seed, 1, i]); the shared parts are mixed once.
    let stream = SeedPrefix::new(&[seed, 1]);
    run_chunks(
        0,
        n_emit,
        |i| {
            let mut rng = Rng32::new(stream.hash(&[i]));
            let (li, p) = scene.light_picker.pick(rng.uniform())?;
            let light = &scene.lights[li];
            let (u_pos, u_dir) = (rng.uniform2(), rng.uniform2());
            let e = light.sample_le(u_pos, u_dir, scene.textures())?;
            let mut ray = if light.is_infinite() { scene.photon_entry(e.ray) } else { e.ray };
            if scene.has_media() {
                ray.medium = scene.medium_at(ray.o, ray.d);
            }
            Some((Emitted { ray, flux: e.flux, light: li as u32 }, p, rng))
        },
        scene,
        store,
        colour,
        1.0 / n_emit.max(1) as f32,
        bias,
        watch,
        hits,
        &mut Vec::new(),
    );
}

/// Traces caustic photons aimed at the bounding spheres `targets` (of mirrors, metals and glass:
/// `specular_targets`) until exactly `n_store` are stored, or `cap` have been emitted.
///
/// Photons are emitted in index order (in parallel chunks read in order), so "the first
/// `n_store` hits" is the same set on any thread count. As in Jensen's photon tracing loop (emit
/// until enough are stored, then scale the stored photons by 1 / the number emitted), every
/// stored photon's power is divided by the photons emitted up to and including the one that
/// made the last stored hit: photons that stored nothing count, those emitted after it (traced
/// in the same batch) do not. When that photon stored more than one hit (it went on through a
/// mirror part after its first caustic hit), its hits past the `n_store`th are dropped.
#[allow(clippy::too_many_arguments)]
pub fn trace_caustic(
    scene: &Scene,
    targets: &[(Vec3, f32)],
    n_store: u64,
    cap: u64,
    seed: u64,
    bias: f32,
    colour: PhotonColour,
    watch: Watch,
) -> PhotonPass {
    if targets.is_empty() || n_store == 0 {
        return PhotonPass::default();
    }
    let mut hits = PhotonHits::default();
    // The photon index of each stored hit, to know how many were emitted up to the last one.
    let mut sources: Vec<u64> = Vec::new();
    let mut emitted = 0u64;
    // The first batch emits as many as are wanted; later ones what the hits per photon so far
    // say is missing, with a tenth more (the batch size changes the work, not the result).
    let mut batch = n_store.max(CHUNK * 4);
    // Every photon's stream is hash_seed(&[seed, 2, i]); the shared parts are mixed once.
    let stream = SeedPrefix::new(&[seed, 2]);
    while (hits.len() as u64) < n_store && emitted < cap && !watch.cancelled() {
        let n = batch.min(cap - emitted);
        let (mut h, mut s) = (PhotonHits::default(), Vec::new());
        run_chunks(
            emitted,
            n,
            |i| {
                let mut rng = Rng32::new(stream.hash(&[i]));
                let (li, p) = scene.light_picker.pick(rng.uniform())?;
                let light = &scene.lights[li];
                let (e, uv) = emit_towards(light, targets, &mut rng)?;
                let flux = e.flux * light.texture_factor(uv, e.ray.d, scene.textures());
                let mut ray = if light.is_infinite() { scene.photon_entry(e.ray) } else { e.ray };
                // As in the global pass: a light inside a medium emits into it.
                if scene.has_media() {
                    ray.medium = scene.medium_at(ray.o, ray.d);
                }
                Some((Emitted { ray, flux, light: li as u32 }, p, rng))
            },
            scene,
            Store::Caustic,
            colour,
            1.0,
            bias,
            Watch { progress: None, ..watch },
            &mut h,
            &mut s,
        );
        hits.append(h);
        sources.extend(s);
        emitted += n;
        watch.advance(n);
        let missing = n_store.saturating_sub(hits.len() as u64);
        let per_photon = hits.len() as f64 / emitted as f64;
        batch = if per_photon > 0.0 { (missing as f64 / per_photon * 1.1) as u64 } else { emitted.saturating_mul(2) }
            .max(CHUNK * 4);
    }
    if (hits.len() as u64) >= n_store && !watch.cancelled() {
        hits.truncate(n_store as usize);
        emitted = sources[n_store as usize - 1] + 1;
    }
    let scale = 1.0 / emitted.max(1) as f32;
    hits.iter_mut().for_each(|h| h.flux = (h.flux.get() * scale).into());
    let capped = (hits.len() as u64) < n_store;
    PhotonPass { hits, emitted, capped, cancelled: watch.cancelled() }
}

/// A photon leaving a light: its ray and the flux it carries (before dividing by the number of
/// photons emitted and by the probability of having chosen the light).
#[derive(Clone, Copy, Debug)]
struct Emitted {
    ray: Ray,
    flux: Color,
    /// The light's index in the scene (its spectrum in spectral mode).
    light: u32,
}

/// Emits photons `first .. first + n` in fixed chunks, in parallel, each chunk's hits into its
/// own buffer of `hits` (its old contents replaced, its buffers reused), each stored flux
/// multiplied by `scale` (1 / photons emitted, when known beforehand). Once the watch's cancel
/// flag is set, chunks not yet started are skipped. For the caustic map, `sources` receives the
/// index of the photon that made each hit.
#[allow(clippy::too_many_arguments)]
fn run_chunks(
    first: u64,
    n: u64,
    emit: impl Fn(u64) -> Option<(Emitted, f32, Rng32)> + Sync,
    scene: &Scene,
    store: Store,
    colour: PhotonColour,
    scale: f32,
    bias: f32,
    watch: Watch,
    hits: &mut PhotonHits,
    sources: &mut Vec<u64>,
) {
    let chunks = n.div_ceil(CHUNK) as usize;
    let mut chunk_sources: Vec<Vec<u64>> = vec![Vec::new(); chunks];
    hits.reset(chunks).par_iter_mut().zip(&mut chunk_sources).enumerate().for_each(|(c, (out, sources))| {
        // Room for one stored hit per global photon (a closed room stores one or two), so
        // threads do not take turns in the allocator growing their buffers; caustic photons
        // are mostly not stored.
        out.reserve(match store {
            Store::All => 2 * CHUNK as usize,
            Store::Indirect => CHUNK as usize,
            Store::Media | Store::Volume => 4 * CHUNK as usize,
            Store::Caustic => 0,
        });
        if watch.cancelled() {
            return;
        }
        let start = first + c as u64 * CHUNK;
        let end = (start + CHUNK).min(first + n);
        for i in start..end {
            if let Some((e, p_light, mut rng)) = emit(i) {
                let mut flux = e.flux / p_light;
                // Spectral photons draw their wavelengths after everything RGB ones draw at
                // emission, so RGB photons are as they were.
                let wl = (colour != PhotonColour::Rgb).then(|| Wavelengths::sample(rng.uniform()));
                if let Some(wl) = &wl {
                    flux = scene.emission_in(flux, e.light, Some(wl));
                }
                if flux.max_element() > 0.0 && flux.is_finite() {
                    let xyz = colour == PhotonColour::SpectralXyz;
                    trace_photon(scene, e.ray, flux, &mut rng, store, bias, wl, xyz, out);
                    if store == Store::Caustic {
                        sources.resize(out.len(), i);
                    }
                }
            }
        }
        if scale != 1.0 {
            out.iter_mut().for_each(|h| h.flux = (h.flux.get() * scale).into());
        }
        watch.advance(end - start);
    });
    sources.clear();
    for s in &chunk_sources {
        sources.extend_from_slice(s);
    }
}

/// Follows one photon, appending its stored hits to `out`. In spectral mode (`wl`) `flux` holds
/// the power at the photon's wavelengths, BSDFs are lifted to them (dispersive glass keeps the
/// hero alone), and each stored hit's power is converted to linear sRGB, or with `xyz` to CIE
/// XYZ.
#[allow(clippy::too_many_arguments)]
pub fn trace_photon(
    scene: &Scene,
    mut ray: Ray,
    mut flux: Color,
    rng: &mut Rng32,
    store: Store,
    bias: f32,
    mut wl: Option<Wavelengths>,
    xyz: bool,
    out: &mut Vec<PhotonHit>,
) {
    let stored = |flux: Color, wl: &Option<Wavelengths>| match wl {
        Some(wl) if xyz => Color::from_array(wl.to_xyz(flux).map(|c| c.max(0.0))),
        Some(wl) => wl.to_srgb(flux),
        None => flux,
    };
    let caustic_only = store == Store::Caustic;
    let mut only_specular = true;
    // No diffuse bounce and no scattering in a medium so far (`FOCUSED`).
    let mut only_focusing = true;
    // Scattering events so far (passing through a mask is none).
    let mut depth = 0;
    for _ in 0..MAX_BOUNCES {
        let hit = scene.intersect(&ray, f32::INFINITY);
        if ray.medium != crate::geometry::NO_MEDIUM {
            // Through a medium: a free flight, which may end in a scattering event first.
            let medium = &scene.media[ray.medium as usize];
            let t_max = hit.as_ref().map_or(f32::INFINITY, |h| h.t);
            // A heterogeneous medium draws its further numbers from the photon's own stream (the
            // homogeneous kind draws none, so its photons are as before).
            let (u_channel, u) = (rng.uniform(), rng.uniform());
            let ms = medium.sample_distance(&ray, t_max, flux, u_channel, u, rng, wl.as_ref());
            let before = flux;
            flux *= ms.weight;
            if ms.scattered {
                if caustic_only {
                    return;
                }
                let p = ray.at(ms.t);
                if matches!(store, Store::Media | Store::Volume) {
                    let flux = stored(flux, &wl);
                    out.push(PhotonHit {
                        p,
                        dir: ray.d,
                        flux: flux.into(),
                        flags: VOLUME,
                        depth: depth as u8,
                        n: Vec3::ZERO,
                    });
                }
                let s = medium.phase().sample(-ray.d, rng.uniform2());
                // Roulette keeps the photon's power as at a surface (`scatter_photon`).
                let q = (flux.sum() / before.sum()).min(1.0);
                if !(q > 0.0) || rng.uniform() >= q {
                    return;
                }
                flux /= q;
                if !flux.is_finite() {
                    return;
                }
                depth += 1;
                only_specular = false;
                only_focusing = false;
                ray = Ray { o: p, d: s.wi, medium: ray.medium };
                continue;
            }
            if !(flux.max_element() > 0.0) || !flux.is_finite() {
                return;
            }
        }
        // Read where the intersection wrote it (a copy stalled on those stores).
        let Some(hit) = &hit else { return };
        let wo = -ray.d;
        let bsdf = scene.bsdf_for(hit, wo, wl.as_mut(), &mut flux);
        // Plain emitters absorb; a reflecting emitter (one with a BSDF) scatters like any surface.
        if bsdf.is_black() {
            return;
        }
        if bsdf.has_smooth() {
            let caustic = depth > 0 && only_specular;
            let n = bsdf.normal();
            if caustic_only {
                if caustic {
                    let flux = stored(flux, &wl);
                    out.push(PhotonHit {
                        p: hit.p,
                        dir: ray.d,
                        flux: flux.into(),
                        flags: CAUSTIC,
                        depth: depth as u8,
                        n,
                    });
                }
                // The mirror or glass part of a mixed material (or plastic's coating) can still
                // send it on along an L S+ D path.
                if !bsdf.has_delta() {
                    return;
                }
            } else {
                let flags = if depth == 0 {
                    DIRECT
                } else if caustic {
                    CAUSTIC | FOCUSED
                } else if only_focusing {
                    FOCUSED
                } else {
                    0
                };
                if depth > 0 || matches!(store, Store::All | Store::Volume) {
                    // (`Store::Indirect` and `Store::Media` leave the first hit to direct light.)
                    let flux = stored(flux, &wl);
                    out.push(PhotonHit { p: hit.p, dir: ray.d, flux: flux.into(), flags, depth: depth as u8, n });
                }
            }
        }
        let Some((wi, scattered, flags)) = scatter_photon(&bsdf, wo, flux, rng) else { return };
        if !flags.is_null() {
            depth += 1;
        }
        if flags.is_diffuse() {
            only_focusing = false;
        }
        if !flags.is_specular() {
            only_specular = false;
            if caustic_only {
                return;
            }
        }
        flux = scattered;
        let medium = scene.medium_after(hit, wi, ray.medium);
        ray = hit.spawn(wi, bias);
        ray.medium = medium;
    }
}

/// Scatters a photon carrying `flux` that arrived from direction `wo`: the BSDF samples a lobe
/// and a direction (importance transport, weighted by that lobe: `Bsdf::sample_lobe`), and
/// Russian roulette on the throughput decides whether it goes on (Jensen 2001 sec. 2.3: survive
/// with the ratio of the scattered to the incident flux, averaged over the channels, then
/// divide by it, so the photon's mean power stays the same). Returns the new direction, flux
/// and the lobe's kind, or `None` when the photon is absorbed.
#[inline(always)]
pub fn scatter_photon(
    bsdf: &Bsdf,
    wo: Vec3,
    flux: Color,
    rng: &mut Rng32,
) -> Option<(Vec3, Color, crate::material::bxdf::LobeFlags)> {
    let s = bsdf.sample_lobe(wo, rng.uniform(), rng.uniform2(), Transport::Importance)?;
    let scattered = flux * s.weight;
    let q = (scattered.sum() / flux.sum()).min(1.0);
    if !(q > 0.0) || rng.uniform() >= q {
        return None;
    }
    let flux = scattered / q;
    (flux.is_finite() && flux.max_element() > 0.0).then_some((s.wi, flux, s.flags))
}

/// Most caustic-photon targets made from instances: beyond it, the instances of each group
/// share one bounding sphere (a photon looks at every target when it is emitted).
const MAX_INSTANCE_TARGETS: usize = 64;

/// Where caustic photons are aimed (Jensen 1996's projection map): the bounding spheres of the
/// scene's objects whose material can focus light into caustics (smooth mirrors, metals, glass,
/// plastic coatings: `Plain::casts_caustics`), and of the instances of groups holding any (each
/// instance's, or one around all of a group's instances when there would be too many).
pub fn specular_targets(scene: &Scene) -> Vec<(Vec3, f32)> {
    let m = &scene.materials;
    let mut targets: Vec<(Vec3, f32)> =
        scene.objects.iter().filter(|o| m.casts_caustics(o.material)).map(|o| (o.center, o.radius)).collect();
    let groups = scene.instances.group_count();
    let group_specular: Vec<bool> =
        (0..groups).map(|g| scene.instances.group_materials(g).any(|k| m.casts_caustics(k))).collect();
    let boxes: Vec<(u32, crate::geometry::Aabb)> =
        scene.instances.instance_bounds().filter(|(g, _)| group_specular[*g as usize]).collect();
    if boxes.len() <= MAX_INSTANCE_TARGETS {
        targets.extend(boxes.iter().map(|(_, b)| b.bounding_sphere()));
        return targets;
    }
    let mut per_group = vec![crate::geometry::Aabb::EMPTY; groups];
    for (g, b) in &boxes {
        per_group[*g as usize] = per_group[*g as usize].union(*b);
    }
    targets.extend(per_group.into_iter().filter(|b| !b.is_empty()).map(|b| b.bounding_sphere()));
    targets
}

/// Solid angle and cone of a target sphere seen from `p`: (axis, cos of the half-angle, solid
/// angle); the whole sphere of directions when `p` is inside it.
fn cone(p: Vec3, (c, r): (Vec3, f32)) -> (Vec3, f32, f32) {
    let v = c - p;
    let d2 = v.length_squared();
    if d2 <= r * r {
        return (Vec3::Z, -1.0, 4.0 * PI);
    }
    let d = d2.sqrt();
    let cos_max = (1.0 - r * r / d2).max(0.0).sqrt();
    (v / d, cos_max, 2.0 * PI * (1.0 - cos_max))
}

/// Emits a photon aimed at the specular targets. The direction (or, for a light at infinity,
/// the position) is drawn from a mixture over the targets' cones (disks), and the flux divided
/// by the mixture's density, so the caustic photons are an unbiased sample of the light's
/// emission restricted to the directions that can reach a mirror or glass object.
fn emit_towards(light: &Light, targets: &[(Vec3, f32)], rng: &mut Rng32) -> Option<(Emitted, Vec2)> {
    let (u_pos, u_pick, u_dir) = (rng.uniform2(), rng.uniform(), rng.uniform2());
    match *light {
        Light::Directional { direction, irradiance, disk } => {
            return towards_from_infinity(direction, irradiance, disk.center, disk.radius, targets, u_pick, u_dir);
        }
        Light::Environment(env) => {
            // A direction by the environment's own sampling, then a point aimed at the targets.
            let (wi, radiance, pdf) = env.sample(u_pos)?;
            if !(pdf > 0.0) {
                return None;
            }
            return towards_from_infinity(
                -wi,
                radiance / pdf,
                env.disk.center,
                env.disk.radius,
                targets,
                u_pick,
                u_dir,
            );
        }
        _ => {}
    }
    // Position (on area lights), then a direction towards one of the targets.
    let (p, p_error, n, pos_weight, radiance_like, uv) = match *light {
        Light::Point { position, intensity } => (position, Vec3::ZERO, Vec3::ZERO, 1.0, intensity, Vec2::ZERO),
        Light::Spot(crate::light::Spot { position, .. })
        | Light::Projector(crate::light::Projector { position, .. }) => {
            (position, Vec3::ZERO, Vec3::ZERO, 1.0, Color::ONE, Vec2::ZERO)
        }
        Light::Area { shape, radiance, .. } => {
            let s = shape.sample_area(u_pos)?;
            (s.p, s.p_error, s.n, shape.area(), radiance, s.uv)
        }
        Light::Directional { .. } | Light::Environment(_) => unreachable!(),
    };
    // Cones are recomputed rather than stored: a photon allocates nothing.
    let cones = || targets.iter().map(|&t| cone(p, t));
    let j = pick(cones().map(|c| c.2), u_pick)?;
    let total: f32 = cones().map(|c| c.2).sum();
    let (axis, cos_max, _) = cone(p, targets[j]);
    let d = Frame::from_z(axis).to_world(uniform_cone(u_dir, cos_max));
    let covering = cones().filter(|(a, cm, _)| d.dot(*a) >= *cm).count().max(1);
    let pdf_dir = covering as f32 / total;
    let emitted = match *light {
        Light::Point { .. } => radiance_like,
        Light::Spot(_) | Light::Projector(_) => light.intensity_towards(d),
        Light::Area { .. } => {
            let cos = n.dot(d);
            if cos <= 0.0 {
                return None;
            }
            radiance_like * cos * pos_weight
        }
        Light::Directional { .. } | Light::Environment(_) => unreachable!(),
    };
    let ray = if n == Vec3::ZERO { Ray::new(p, d) } else { Ray::spawn(p, p_error, n, d, 0.0) };
    Some((Emitted { ray, flux: emitted / pdf_dir, light: crate::geometry::NO_LIGHT }, uv))
}

/// A photon travelling along `direction` from infinity, through a point of the disks the targets
/// project perpendicular to it (chosen in proportion to their areas), carrying `irradiance`
/// over the density of that point; it starts outside the bounding sphere (`center`, `radius`)
/// of the finite geometry.
fn towards_from_infinity(
    direction: Vec3,
    irradiance: crate::math::Color,
    center: Vec3,
    radius: f32,
    targets: &[(Vec3, f32)],
    u_pick: f32,
    u_dir: crate::math::Vec2,
) -> Option<(Emitted, Vec2)> {
    let frame = Frame::from_z(direction);
    let j = pick(targets.iter().map(|t| PI * t.1 * t.1), u_pick)?;
    let total: f32 = targets.iter().map(|t| PI * t.1 * t.1).sum();
    let (c, r) = targets[j];
    let disk = concentric_disk(u_dir) * r;
    let q = c + frame.x * disk.x + frame.y * disk.y;
    let covering = targets
        .iter()
        .filter(|(tc, tr)| {
            let v = q - *tc;
            let off = v - direction * v.dot(direction);
            off.length_squared() <= tr * tr
        })
        .count()
        .max(1);
    let pdf_area = covering as f32 / total;
    let back = (center - q).dot(-direction) + radius;
    let o = q - direction * back.max(r);
    Some((
        Emitted { ray: Ray::new(o, direction), flux: irradiance / pdf_area, light: crate::geometry::NO_LIGHT },
        Vec2::ZERO,
    ))
}

/// Index chosen from `weights` in proportion to them, by the uniform number `u`.
fn pick(weights: impl Iterator<Item = f32> + Clone, u: f32) -> Option<usize> {
    let total: f32 = weights.clone().sum();
    if !(total > 0.0) {
        return None;
    }
    let mut x = u * total;
    let mut last = None;
    for (i, w) in weights.enumerate() {
        if x < w {
            return Some(i);
        }
        x -= w;
        if w > 0.0 {
            last = Some(i);
        }
    }
    last
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::{Classic, ClassicKind};

    /// A whole path keeps to max_depth: at camera bounce b photons may have scattered
    /// max_depth - b times, none beyond the limit, and the packed byte keeps flags and depth.
    #[test]
    fn photon_depths_keep_paths_within_the_limit() {
        assert_eq!(photon_depth_limit(8, 1), Some(7));
        assert_eq!(photon_depth_limit(8, 8), Some(0));
        assert_eq!(photon_depth_limit(8, 9), None);
        assert_eq!(photon_depth_limit(1000, 2), Some(MAX_PHOTON_DEPTH));
        for (flags, depth) in [(0, 0), (DIRECT, 5), (CAUSTIC, MAX_PHOTON_DEPTH as u8)] {
            let h = PhotonHit { p: Vec3::ZERO, dir: Vec3::Z, flux: Color::ONE.into(), flags, depth, n: Vec3::Z };
            let packed = packed_flags(&h);
            assert_eq!((packed & (DIRECT | CAUSTIC), packed_depth(packed)), (flags, u32::from(depth)));
        }
    }

    #[test]
    fn photon_roulette_keeps_mean_power() {
        // Russian roulette on the throughput: the expected scattered power equals the albedo times
        // the incoming power, per channel, for a coloured diffuse + mirror material.
        let wo = Vec3::new(0.2, 0.1, 1.0).normalize();
        let m = Classic {
            kind: ClassicKind::Reflective,
            color: Color::new(0.9, 0.6, 0.3),
            kd: 0.5,
            kr: 0.3,
            ..Classic::default()
        };
        let b = Bsdf::new(Frame::from_z(Vec3::Z), Vec3::Z, true, m.lobes(true));
        let mut rng = Rng32::new(77);
        let n = 400_000;
        let mut sum = Color::ZERO;
        let flux = Color::new(1.0, 0.8, 0.5);
        for _ in 0..n {
            if let Some((_, f, _)) = scatter_photon(&b, wo, flux, &mut rng) {
                // Photons keep their power averaged over the channels.
                assert!((f.sum() - flux.sum()).abs() < 1e-4, "{f}");
                sum += f;
            }
        }
        let mean = sum / n as f32;
        let expected = flux * (Color::new(0.9, 0.6, 0.3) * 0.5 + Color::splat(0.3));
        // Standard error per channel is below 0.0015 here; allow 4 sigma.
        assert!((mean - expected).abs().max_element() < 0.006, "{mean} vs {expected}");
    }
}
