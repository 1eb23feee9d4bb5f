//! First-hit AOVs (`film::aov`): what a camera ray meets first, found by one more intersection
//! per camera sample when a render asks for them. Ray integrators add them sample by sample in
//! the tile loop; integrators whose film is not made of camera samples per pixel (SPPM, the
//! light tracer) get them afterwards from [`add_first_hits`], for the same sample indices, so
//! every integrator's AOVs are the same images.

use super::RenderSettings;
use crate::film::Film;
use crate::film::aov::FirstHit;
use crate::geometry::Ray;
use crate::scene::Scene;
use rayon::prelude::*;

/// Most first-hit channels a list can have (each kind once: 3 + 1 + 3 + 2 + 3 + 3).
pub const MAX_FIRST_HIT_CHANNELS: usize = 15;

/// What `ray` (a camera ray) meets first; all zero where it leaves the scene.
pub fn first_hit(scene: &Scene, ray: &Ray) -> FirstHit {
    let Some(hit) = scene.intersect(ray, f32::INFINITY) else { return FirstHit::default() };
    let albedo = scene.bsdf(&hit, -ray.d).diffuse_albedo();
    let uv = hit.uv();
    FirstHit {
        albedo: albedo.to_array(),
        // The ray's direction is a unit vector, so its parameter is the distance.
        depth: hit.t,
        position: hit.p.to_array(),
        uv: [uv.x, uv.y],
        sh_normal: hit.ns.to_array(),
        geo_normal: hit.ng.to_array(),
    }
}

/// Adds the first-hit AOVs of each pixel's camera samples from index `settings.first_sample +
/// before[pixel]` up to its count in `film` (`before`: the counts, tile by tile, the film held
/// when the render started).
pub fn add_first_hits(scene: &Scene, settings: &RenderSettings, film: &mut Film, before: &[Vec<u32>]) {
    if !film.aovs.has_first_hit() {
        return;
    }
    let aovs = film.aovs.clone();
    film.tiles.par_iter_mut().zip(before).for_each(|(tile, before)| {
        let mut values = [0.0f32; MAX_FIRST_HIT_CHANNELS];
        for j in 0..tile.height {
            for i in 0..tile.width {
                let k = (j * tile.width + i) as usize;
                let (x, y) = (tile.x0 + i, tile.y0 + j);
                let mut pixel = settings.pixel_sampler(x, y);
                let from = settings.first_sample.saturating_add(before[k]);
                for index in from..settings.first_sample.saturating_add(tile.count[k]) {
                    let (_, ray, weight) = settings.camera_sample_of(scene, x, y, &mut pixel, index);
                    aovs.first_hit_values(&first_hit(scene, &ray), &mut values);
                    tile.add_first_hit(k, &values, weight);
                }
            }
        }
    });
}
