//! SPPM's visible points (a camera path's first non-specular hit, what a pixel gathers
//! photons at) and the gather itself: the photons around a point, their flux through its BSDF
//! and the counts of each disc.

use super::grid::{Found, PhotonGrid};
use crate::geometry::Hit;
use crate::integrator::layers::LayerPath;
use crate::material::bsdf::Bsdf;
use crate::material::bxdf::Transport;
use crate::math::{Color, PackedColor, Vec3};
use crate::photon::PhotonHits;
use crate::photon::trace::{self, PhotonHit};
use crate::scene::Scene;

/// A camera path's first non-specular hit. It keeps the hit, not its BSDF: the BSDF is made
/// again from the hit when the pixel gathers (the same BSDF, once per pixel and iteration), as a
/// BSDF with its lobes inline is three times the size of the hit and a point per pixel is most of
/// SPPM's memory. A Lambertian surface keeps what the gather reads of its BSDF instead.
#[derive(Clone, Copy)]
pub(super) struct VisiblePoint {
    pub(super) surface: PointSurface,
    /// The throughput as RGB (in spectral mode too: `CameraWalk::beta_rgb`).
    pub(super) beta: PackedColor,
    /// The layers of the light gathered there.
    pub(super) layer: LayerPath,
    /// Most scattering events a photon gathered there may have had, so that whole paths keep
    /// to the depth limit (`trace::photon_depth_limit`).
    pub(super) photon_depth: u8,
}

/// What the gather reads of a visible point's surface.
#[derive(Clone, Copy)]
pub(super) enum PointSurface {
    /// One Lambertian lobe seen from above both its normals (RGB mode): the BSDF's value, the
    /// same for every direction above, and its shading and geometric normals, taken from the
    /// camera path's BSDF, so that the gather makes none (making it was a tenth of the gather).
    Lambert { p: Vec3, ns: Vec3, ng: Vec3, f: Color },
    /// Any other surface: what its BSDF is made from again (`Shading::hit`) and the direction
    /// towards the viewer.
    General { at: Shading, wo: Vec3 },
}

impl PointSurface {
    /// The surface at `hit` of BSDF `bsdf` (made for the viewer at `wo`); `rgb` when that is
    /// the BSDF the gather would make (not a spectral path's lifted one).
    pub(super) fn of(hit: &Hit, bsdf: &Bsdf, wo: Vec3, rgb: bool) -> Self {
        let (ns, ng) = (bsdf.normal(), bsdf.geometric_normal());
        if rgb && bsdf.lambert_albedo().is_some() && ns.dot(ng) > 0.0 {
            PointSurface::Lambert { p: hit.p, ns, ng, f: bsdf.f(wo, ns, Transport::Radiance) }
        } else {
            PointSurface::General { at: Shading::of(hit), wo }
        }
    }
}

/// The part of a hit its BSDF is made from: a hit without its distance, error bound and light.
#[derive(Clone, Copy)]
pub(super) struct Shading {
    p: Vec3,
    ng: Vec3,
    ns: Vec3,
    param: crate::geometry::SurfaceParam,
    material: u32,
    prim: u32,
}

impl Shading {
    pub(super) fn of(h: &Hit) -> Self {
        Shading { p: h.p, ng: h.ng, ns: h.ns, param: h.param, material: h.material, prim: h.prim }
    }

    /// A hit that makes the same BSDF as the one this was taken from (`Scene::bsdf` reads none
    /// of the fields left out).
    fn hit(&self) -> Hit {
        Hit {
            t: 0.0,
            p: self.p,
            p_error: Vec3::ZERO,
            ng: self.ng,
            ns: self.ns,
            param: self.param,
            material: self.material,
            light: crate::geometry::NO_LIGHT,
            prim: self.prim,
        }
    }
}

/// What a pixel's discs took from one iteration's photons (`gather`).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(super) struct Gathered {
    /// Photons within the pixel's radius (M of its schedule) and the flux the BSDF passes
    /// towards the camera from those the near disc estimates, with its part that came only
    /// through mirrors and glass.
    pub(super) m_near: u32,
    pub(super) near: Color,
    pub(super) near_caustic: Color,
    /// The same of the wide disc (nothing when it is unused).
    pub(super) m_wide: u32,
    pub(super) wide: Color,
}

/// The photons around visible point `v`: within radius `r` every photon, or with a wide disc of
/// radius `r_wide` > 0 the focused photons (`trace::FOCUSED`: caustics, and light through glossy
/// surfaces) within `r` and the others within `r_wide`. Every
/// photon within a disc counts in its M (Hachisuka and Jensen 2009; pbrt-v4), whether or not
/// the BSDF passes its light.
pub(super) fn gather(
    scene: &Scene,
    v: &VisiblePoint,
    r: f32,
    r_wide: f32,
    grid: &PhotonGrid,
    hits: &PhotonHits,
) -> Gathered {
    let mut g = Gathered::default();
    // A Lambertian BSDF's value is the same for every direction above the surface: worked out
    // once (the same value `f` gives each photon), not per photon.
    let made;
    let (p, ns, ng, constant, general) = match &v.surface {
        PointSurface::Lambert { p, ns, ng, f } => (*p, *ns, *ng, Some(*f), None),
        PointSurface::General { at, wo } => {
            made = scene.bsdf(&at.hit(), *wo);
            let (ns, ng) = (made.normal(), made.geometric_normal());
            let constant =
                (made.lambert_albedo().is_some() && ns.dot(ng) > 0.0).then(|| made.f(*wo, ns, Transport::Radiance));
            (at.p, ns, ng, constant, Some((&made, *wo)))
        }
    };
    let wide = r_wide > 0.0;
    let r2 = r * r;
    let reach = if wide { r_wide.max(r) } else { r };
    // Which disc a found photon counts in (and whether it is counted at all): light that may
    // still be focused (through mirrors, glass or glossy surfaces only) stays in the near disc;
    // light after a diffuse bounce is smooth enough for the wide one. The grid knows which is
    // which, so focused photons beyond r are passed over unread.
    #[inline(always)]
    fn disc_of(g: &mut Gathered, found: Found, wide: bool, r2: f32) -> Option<bool> {
        let within_r = !wide || found.d2 <= r2;
        g.m_near += u32::from(within_r);
        if !wide {
            return Some(false);
        }
        if found.focused {
            return within_r.then_some(false);
        }
        g.m_wide += 1;
        Some(true)
    }
    #[inline(always)]
    fn add(g: &mut Gathered, in_wide: bool, f: Color, ph: &PhotonHit) {
        let flux = ph.flux.get();
        if in_wide {
            g.wide += f * flux;
        } else {
            g.near += f * flux;
            if ph.flags & trace::CAUSTIC != 0 {
                g.near_caustic += f * flux;
            }
        }
    }
    match constant {
        // The usual case, a Lambertian surface: a photon counts when it arrives from above both
        // normals (`wi . ns > 0` also says it is not from behind, the general case's first test).
        Some(c) => {
            let passes = c != Color::ZERO;
            grid.for_each_within(p, reach, |found| {
                let Some(in_wide) = disc_of(&mut g, found, wide, r2) else { return };
                let ph = grid.photon(hits, found);
                let wi = -ph.dir;
                if passes && ph.depth <= v.photon_depth && wi.dot(ng) > 0.0 && wi.dot(ns) > 0.0 {
                    add(&mut g, in_wide, c, ph);
                }
            });
        }
        None => {
            let Some((bsdf, wo)) = general else { unreachable!("a Lambertian point has its constant") };
            // Photons from behind pass only through a transmitting surface (rough glass).
            let both_sides = bsdf.flags().is_transmission();
            grid.for_each_within(p, reach, |found| {
                let Some(in_wide) = disc_of(&mut g, found, wide, r2) else { return };
                let ph = grid.photon(hits, found);
                if (!both_sides && ph.dir.dot(ns) >= 0.0) || ph.depth > v.photon_depth {
                    return;
                }
                let f = bsdf.f(wo, -ph.dir, Transport::Radiance);
                if f != Color::ZERO {
                    add(&mut g, in_wide, f, ph);
                }
            });
        }
    }
    g
}

#[cfg(test)]
mod tests {
    use super::super::{Disc, PixelStats};
    use super::*;
    use std::f32::consts::PI;

    /// A scene of one grey (albedo 0.5) quad in the plane z = 0, facing +z.
    fn grey_quad() -> Scene {
        crate::scene::test_scenes::quad_of("type = \"diffuse\"\ncolor = [0.5, 0.5, 0.5]\nkd = 1")
    }

    /// The visible point at the quad's centre, seen from straight above.
    fn centre_point(scene: &Scene) -> VisiblePoint {
        let hit = scene.intersect(&crate::geometry::Ray::new(Vec3::new(0.0, 0.0, 1.0), -Vec3::Z), f32::INFINITY);
        VisiblePoint {
            surface: PointSurface::General { at: Shading::of(&hit.unwrap()), wo: Vec3::Z },
            beta: Color::ONE.into(),
            layer: LayerPath::CAMERA,
            photon_depth: trace::MAX_PHOTON_DEPTH as u8,
        }
    }

    #[test]
    fn every_photon_in_range_counts_in_m() {
        let scene = grey_quad();
        let v = centre_point(&scene);
        let hit = |p: Vec3, dir: Vec3| PhotonHit { p, dir, flux: Color::ONE.into(), flags: 0, depth: 0, n: Vec3::Z };
        let lit = hit(Vec3::new(0.1, 0.0, 0.0), -Vec3::Z);
        let mut hits = PhotonHits::from_vec(vec![
            lit,                                     // in range, from above: lit
            hit(Vec3::new(0.0, -0.2, 0.0), Vec3::Z), // in range, from below: no light, counted
            hit(Vec3::new(0.0, 0.0, 0.0), Vec3::X),  // grazing: no light, counted
            hit(Vec3::new(0.6, 0.0, 0.0), -Vec3::Z), // out of range
        ]);
        let grid = PhotonGrid::build(&mut hits, 0.5, Vec3::splat(-1.0));
        let g = gather(&scene, &v, 0.5, 0.0, &grid, &hits);
        assert_eq!(g.m_near, 3);
        assert!((g.near.r() - 0.5 / PI).abs() < 1e-6, "{g:?}");
        // Kept as a Lambertian surface (what the gather reads of the camera path's BSDF), the
        // point gathers the same, bit for bit.
        let PointSurface::General { at, wo } = v.surface else { unreachable!() };
        let surface = PointSurface::of(&at.hit(), &scene.bsdf(&at.hit(), wo), wo, true);
        assert!(matches!(surface, PointSurface::Lambert { .. }));
        assert_eq!(gather(&scene, &VisiblePoint { surface, ..v }, 0.5, 0.0, &grid, &hits), g);
        // A photon of more bounces than the point allows is counted in M but brings no light.
        let mut deep = PhotonHits::from_vec(vec![PhotonHit { depth: 3, ..lit }]);
        let grid = PhotonGrid::build(&mut deep, 0.5, Vec3::splat(-1.0));
        let g = gather(&scene, &VisiblePoint { photon_depth: 2, ..v }, 0.5, 0.0, &grid, &deep);
        assert_eq!((g.m_near, g.near), (1, Color::ZERO));
        let g = gather(&scene, &VisiblePoint { photon_depth: 3, ..v }, 0.5, 0.0, &grid, &deep);
        assert!(g.m_near == 1 && (g.near.r() - 0.5 / PI).abs() < 1e-6, "{g:?}");
    }

    #[test]
    fn indirect_photons_are_gathered_over_the_wide_disc() {
        let scene = grey_quad();
        let v = centre_point(&scene);
        let hit = |x: f32, flags: u8| PhotonHit {
            p: Vec3::new(x, 0.0, 0.0),
            dir: -Vec3::Z,
            flux: Color::ONE.into(),
            flags,
            depth: 1,
            n: Vec3::Z,
        };
        let mut hits = PhotonHits::from_vec(vec![
            hit(0.1, 0),                                // indirect within r: the wide disc's
            hit(0.4, 0),                                // indirect within the wide disc only
            hit(0.15, trace::CAUSTIC | trace::FOCUSED), // caustic within r: the near disc's
            hit(0.5, trace::FOCUSED),                   // focused beyond r: left out
            hit(0.7, 0),                                // beyond both
        ]);
        let grid = PhotonGrid::build(&mut hits, 1.2, Vec3::splat(-1.0));
        let f = 0.5 / PI;
        let g = gather(&scene, &v, 0.2, 0.6, &grid, &hits);
        // M of the near disc: every photon within r; of the wide disc: its own photons.
        assert_eq!((g.m_near, g.m_wide), (2, 2));
        assert!((g.near.r() - f).abs() < 1e-6 && g.near_caustic == g.near, "{g:?}");
        assert!((g.wide.r() - 2.0 * f).abs() < 1e-6, "{g:?}");
        // Light through a glossy surface only (focused, not a caustic) stays near too.
        let mut glossy = PhotonHits::from_vec(vec![hit(0.1, trace::FOCUSED)]);
        let grid_glossy = PhotonGrid::build(&mut glossy, 1.2, Vec3::splat(-1.0));
        let g = gather(&scene, &v, 0.2, 0.6, &grid_glossy, &glossy);
        assert!((g.m_near, g.m_wide) == (1, 0) && (g.near.r() - f).abs() < 1e-6 && g.near_caustic == Color::ZERO);
        // Without a wide disc: every photon within r in the near one.
        let g = gather(&scene, &v, 0.2, 0.0, &grid, &hits);
        assert_eq!((g.m_near, g.m_wide, g.wide), (2, 0, Color::ZERO));
        assert!((g.near.r() - 2.0 * f).abs() < 1e-6 && (g.near_caustic.r() - f).abs() < 1e-6, "{g:?}");
        // Each disc shrinks by its own photons: a pixel whose near disc is empty still has its
        // wide disc shrink as photons come into it (where one schedule for both would keep a
        // shadowed pixel's wide disc taking a bright neighbour's light for ever).
        let mut p = PixelStats { ld: PackedColor::ZERO, near: Disc { n: 0.0, r: 0.2, tau: PackedColor::ZERO } };
        let mut wide = Disc { n: 0.0, r: 0.6, tau: PackedColor::ZERO };
        assert_eq!(p.near.update(0, Color::ZERO, 2.0 / 3.0), 1.0);
        let ratio = wide.update(3, Color::splat(3.0), 2.0 / 3.0);
        assert!((ratio - 2.0 / 3.0).abs() < 1e-6 && (wide.r * wide.r - 0.36 * 2.0 / 3.0).abs() < 1e-6);
        assert_eq!((p.near.r, p.near.n), (0.2, 0.0));
        let l = p.radiance(Some(&wide), 1);
        assert!((l.r() - 2.0 / (PI * wide.r * wide.r)).abs() < 1e-4, "{l}");
    }
}
