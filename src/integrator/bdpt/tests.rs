//! The reverse density every technique's weight reads: at a surface reached from `wi`, the
//! density of sampling `wo` must be what `strategy::reverse_pdf` computes from the BSDF seen from
//! `wo` (the BSDF of `wi`'s side for transmission: another relative index, another face).

use super::strategy::reverse_pdf;
use crate::geometry::Ray;
use crate::material::bxdf::Transport;
use crate::math::Vec3;
use crate::sampling::chi2::{Chi2Config, chi2_directions};
use crate::scene::Scene;
use crate::scene::test_scenes::quad_of;
use crate::spectrum::Wavelengths;

/// Where the tests' ray meets the quad.
fn hit_of(scene: &Scene) -> crate::geometry::Hit {
    scene.intersect(&Ray::new(Vec3::new(0.1, 0.05, 1.0), -Vec3::Z), f32::INFINITY).unwrap()
}

#[test]
fn reverse_densities_are_the_densities_of_sampling_from_the_other_direction() {
    let materials = [
        ("roughdielectric", "type = \"roughdielectric\"\nior = 1.5\nalpha = 0.3"),
        ("roughplastic", "type = \"roughplastic\"\ncolor = [0.3, 0.4, 0.5]\nalpha = 0.2"),
        ("principled", "type = \"principled\"\ncolor = [0.7, 0.4, 0.3]\nroughness = 0.4\nspec_trans = 0.6"),
        ("principledthin", "type = \"principledthin\"\ncolor = [0.3, 0.6, 0.3]\nroughness = 0.4\ndiff_trans = 0.8"),
        // Spectral mode: the glass's index at the hero, from either side (the BSDF seen from the
        // other side lifted as the one at hand).
        ("roughdielectric dispersive", "type = \"roughdielectric\"\ndispersion = \"dense flint\"\nalpha = 0.3"),
        ("principled coloured", "type = \"principled\"\ncolor = [0.9, 0.2, 0.1]\nroughness = 0.3\nspec_trans = 0.5"),
    ];
    let arrivals = [
        Vec3::new(0.3, -0.2, 0.9).normalize(),
        Vec3::new(-0.5, 0.1, -0.7).normalize(),
        Vec3::new(0.8, 0.4, 0.3).normalize(),
    ];
    let tests = materials.len() * arrivals.len() * 2;
    for (name, material) in materials {
        // The last two are lifted to wavelengths with the hero at 450 nm.
        let wl = name.contains(' ').then(|| Wavelengths::sample(0.15));
        assert!(wl.is_none_or(|wl| (wl.hero() - 450.0).abs() < 30.0));
        let scene = quad_of(material);
        let bsdf = |wo: Vec3| match wl {
            Some(mut wl) => {
                let mut factor = crate::math::Color::ONE;
                scene.bsdf_for(&hit_of(&scene), wo, Some(&mut wl), &mut factor)
            }
            None => scene.bsdf(&hit_of(&scene), wo),
        };
        let hit = hit_of(&scene);
        for wi in arrivals {
            for mode in [Transport::Radiance, Transport::Importance] {
                // Light (or importance) arrives from `wi`: the surface seen from there samples
                // the next direction; its density must be the reverse density of each direction
                // `wo`, computed as a connection ending at `wo` computes it.
                let from_wi = bsdf(wi);
                let config = Chi2Config { tests, samples: 200_000, ..Chi2Config::with_theta_res(8) };
                chi2_directions(
                    &format!("{name} reverse from {wi} ({mode:?})"),
                    |u, uc| from_wi.sample(wi, uc, u, mode).filter(|s| !s.flags.is_specular()).map(|s| s.wi),
                    |wo| reverse_pdf(&scene, &hit, &bsdf(wo), wo, wi, mode, wl.as_ref()),
                    &config,
                )
                .unwrap_or_else(|report| panic!("{report}"));
            }
        }
    }
}
