//! Tests of the Mitsuba-style lobes (issue 11): conductors, rough dielectrics, plastics, blends
//! and masks. Each is checked for sampling against its density (chi-square), reciprocity of
//! reflection and energy (directional albedo at most 1, exactly 1 where nothing is lost), and
//! against values Mitsuba 3.9.1 gives.

use super::*;
use crate::material::bxdf::{
    CoatingTable, Conductor, Dielectric, FresnelMirror, Lambert, PlasticDiffuse, RoughCoating, RoughConductor,
    RoughDielectric, RoughPlasticDiffuse,
};
use crate::material::fresnel::fresnel_diffuse_reflectance;
use crate::material::microfacet::{Distribution, Microfacet};
use crate::math::{Frame, Vec3};
use crate::sampling::Rng32;
use crate::sampling::chi2::{Chi2Config, chi2_directions};
use crate::sampling::warp::uniform_sphere;

/// Chi-square tests run in this file (for the Sidak correction).
const TESTS: usize = 40;

/// Mitsuba's eta for plastics (polypropylene in air).
const PLASTIC_ETA: f32 = 1.489_587;

fn bsdf_of(lobes: &[Bxdf], wo: Vec3) -> Bsdf<'static> {
    let mut l = Lobes::default();
    for &lobe in lobes {
        l.add(lobe);
    }
    Bsdf::new(Frame::from_z(Vec3::Z), Vec3::Z, front_side(wo, Vec3::Z), l)
}

fn wos() -> [Vec3; 3] {
    [Vec3::new(0.0, 0.0, 1.0), Vec3::new(0.5, 0.2, 0.8).normalize(), Vec3::new(-0.9, 0.1, 0.25).normalize()]
}

fn chi2_bsdf(name: &str, b: &Bsdf, wo: Vec3, mode: Transport) {
    let config = Chi2Config { tests: TESTS, samples: 300_000, ..Chi2Config::with_theta_res(16) };
    chi2_directions(
        name,
        |u, uc| b.sample(wo, uc, u, mode).filter(|s| !s.flags.is_specular()).map(|s| s.wi),
        |wi| b.pdf(wo, wi, mode),
        &config,
    )
    .unwrap_or_else(|report| panic!("{report}"));
}

fn rough_conductors() -> Vec<(String, Bxdf)> {
    let crate::material::conductors::ComplexIor { eta, k, .. } = crate::material::conductors::lookup("Cu").unwrap();
    let mut out = Vec::new();
    for (d, au, av) in
        [(Distribution::Ggx, 0.3, 0.3), (Distribution::Beckmann, 0.1, 0.4), (Distribution::Ggx, 0.05, 0.6)]
    {
        let mf = Microfacet::new(d, au, av);
        out.push((
            format!("rough conductor {d:?} {au}/{av}"),
            Bxdf::RoughConductor(RoughConductor { mf, eta, k, measured: None, scale: Color::ONE }),
        ));
    }
    out
}

fn coating(d: Distribution, alpha: f32) -> (Microfacet, &'static CoatingTable) {
    let mf = Microfacet::new(d, alpha, alpha);
    (mf, CoatingTable::shared(mf, PLASTIC_ETA))
}

fn rough_plastic(d: Distribution, alpha: f32) -> [Bxdf; 2] {
    let (mf, table) = coating(d, alpha);
    let base = Color::new(0.2, 0.5, 0.8);
    [
        Bxdf::RoughCoating(RoughCoating { mf, eta: PLASTIC_ETA, scale: Color::ONE, table }),
        Bxdf::RoughPlasticDiffuse(RoughPlasticDiffuse { d: base, table, d_mean: 0.5 }),
    ]
}

#[test]
fn rough_conductors_sample_their_density() {
    for (name, lobe) in rough_conductors() {
        for wo in wos() {
            chi2_bsdf(&name, &bsdf_of(&[lobe], wo), wo, Transport::Radiance);
        }
    }
}

#[test]
fn rough_dielectrics_sample_their_density_both_ways() {
    for (d, alpha) in [(Distribution::Ggx, 0.2), (Distribution::Beckmann, 0.35)] {
        for eta in [1.5, 1.0 / 1.5] {
            let mf = Microfacet::new(d, alpha, alpha);
            let lobe = Bxdf::RoughDielectric(RoughDielectric { mf, eta, r: Color::ONE, t: Color::ONE });
            for wo in wos() {
                for mode in [Transport::Radiance, Transport::Importance] {
                    chi2_bsdf(&format!("rough dielectric {d:?} {alpha} eta {eta}"), &bsdf_of(&[lobe], wo), wo, mode);
                }
            }
        }
    }
}

#[test]
fn plastics_blends_and_masks_sample_their_density() {
    let smooth = [
        Bxdf::FresnelMirror(FresnelMirror { eta: PLASTIC_ETA, scale: Color::ONE }),
        Bxdf::PlasticDiffuse(PlasticDiffuse { d: Color::new(0.2, 0.5, 0.8), eta: PLASTIC_ETA, d_mean: 0.5 }),
    ];
    let crate::material::conductors::ComplexIor { eta, k, .. } = crate::material::conductors::lookup("Au").unwrap();
    let gold = Bxdf::RoughConductor(RoughConductor {
        mf: Microfacet::new(Distribution::Ggx, 0.15, 0.15),
        eta,
        k,
        measured: None,
        scale: Color::ONE,
    });
    for wo in wos() {
        chi2_bsdf("smooth plastic", &bsdf_of(&smooth, wo), wo, Transport::Radiance);
        for d in [Distribution::Ggx, Distribution::Beckmann] {
            chi2_bsdf(&format!("rough plastic {d:?}"), &bsdf_of(&rough_plastic(d, 0.2), wo), wo, Transport::Radiance);
        }
        // A blend of a diffuse and a rough metal, 30% metal.
        let mut a = Lobes::default();
        a.add(Bxdf::Lambert(Lambert { r: Color::splat(0.5) }));
        let mut b = Lobes::default();
        b.add(gold);
        let mut blend = Lobes::default();
        blend.add_scaled(&a, 0.7);
        blend.add_scaled(&b, 0.3);
        let blended = Bsdf::new(Frame::from_z(Vec3::Z), Vec3::Z, true, blend);
        chi2_bsdf("blend", &blended, wo, Transport::Radiance);
        // A mask: the density of the scattered part is opacity times the lobe's.
        let masked = bsdf_of(&[gold], wo).with_opacity(0.6);
        chi2_bsdf("mask", &masked, wo, Transport::Radiance);
    }
}

#[test]
fn microfacet_reflection_is_reciprocal() {
    let mut rng = Rng32::new(3);
    let mut lobes: Vec<Bxdf> = rough_conductors().into_iter().map(|(_, l)| l).collect();
    lobes.extend(rough_plastic(Distribution::Ggx, 0.25));
    lobes.extend(rough_plastic(Distribution::Beckmann, 0.1));
    lobes.push(Bxdf::PlasticDiffuse(PlasticDiffuse { d: Color::splat(0.4), eta: PLASTIC_ETA, d_mean: 0.4 }));
    for (d, eta) in [(Distribution::Ggx, 1.5), (Distribution::Beckmann, 1.0 / 1.33)] {
        let mf = Microfacet::new(d, 0.3, 0.3);
        lobes.push(Bxdf::RoughDielectric(RoughDielectric { mf, eta, r: Color::ONE, t: Color::ONE }));
    }
    for _ in 0..3000 {
        let (a, b) = (uniform_sphere(rng.uniform2()), uniform_sphere(rng.uniform2()));
        let (a, b) = (Vec3::new(a.x, a.y, a.z.abs()), Vec3::new(b.x, b.y, b.z.abs()));
        for lobe in &lobes {
            let (fab, fba) = (lobe.f(a, b, Transport::Radiance), lobe.f(b, a, Transport::Radiance));
            assert!(
                (fab - fba).abs().max_element() <= 2e-4 * fab.max_element().max(1.0),
                "{lobe:?}: f({a}, {b}) = {fab} but f({b}, {a}) = {fba}"
            );
        }
    }
}

/// Monte Carlo directional albedo of a BSDF: the mean sample weight.
fn albedo(b: &Bsdf, wo: Vec3, n: usize, mode: Transport) -> Color {
    let mut rng = Rng32::new(23);
    let mut sum = Color::ZERO;
    for _ in 0..n {
        if let Some(s) = b.sample(wo, rng.uniform(), rng.uniform2(), mode) {
            sum += s.weight;
        }
    }
    sum / n as f32
}

#[test]
fn energy_is_conserved() {
    // White metals (F = 1) of every roughness reflect at most everything, and nearly everything
    // when almost smooth (Smith shadowing loses a little at grazing angles for rough ones).
    for d in [Distribution::Ggx, Distribution::Beckmann] {
        for alpha in [0.001, 0.01, 0.2, 0.6, 1.0] {
            let lobe = Bxdf::RoughConductor(RoughConductor {
                mf: Microfacet::new(d, alpha, alpha),
                eta: Color::ZERO,
                k: Color::ONE,
                measured: None,
                scale: Color::ONE,
            });
            for wo in wos() {
                let a = albedo(&bsdf_of(&[lobe], wo), wo, 100_000, Transport::Radiance);
                assert!(a.max_element() <= 1.0 + 2e-3, "{d:?} alpha {alpha} at {wo}: albedo {a}");
                if alpha <= 0.01 {
                    assert!(a.min_element() >= 0.995, "{d:?} alpha {alpha} at {wo}: albedo {a}, expected 1");
                }
            }
        }
    }
    // A rough dielectric keeps everything it does not lose to shadowing: reflection plus
    // transmission (counted without the 1/eta^2 of radiance) is 1 when almost smooth.
    for d in [Distribution::Ggx, Distribution::Beckmann] {
        for eta in [1.5, 1.0 / 1.5] {
            for alpha in [0.005, 0.3] {
                let mf = Microfacet::new(d, alpha, alpha);
                let lobe = Bxdf::RoughDielectric(RoughDielectric { mf, eta, r: Color::ONE, t: Color::ONE });
                for wo in wos() {
                    let a = albedo(&bsdf_of(&[lobe], wo), wo, 100_000, Transport::Importance);
                    assert!(a.max_element() <= 1.0 + 3e-3, "{d:?} eta {eta} alpha {alpha} at {wo}: albedo {a}");
                    if alpha < 0.01 {
                        assert!(a.min_element() >= 0.99, "{d:?} eta {eta} alpha {alpha} at {wo}: albedo {a}");
                    }
                }
            }
        }
    }
    // Plastics with a white base lose only what the base cannot send back out through the
    // coating; never more than everything.
    for wo in wos() {
        let smooth = [
            Bxdf::FresnelMirror(FresnelMirror { eta: PLASTIC_ETA, scale: Color::ONE }),
            Bxdf::PlasticDiffuse(PlasticDiffuse {
                d: Color::ONE / ((1.0 - fresnel_diffuse_reflectance(1.0 / PLASTIC_ETA)) * PLASTIC_ETA * PLASTIC_ETA),
                eta: PLASTIC_ETA,
                d_mean: 1.0,
            }),
        ];
        let a = albedo(&bsdf_of(&smooth, wo), wo, 200_000, Transport::Radiance);
        assert!(a.max_element() <= 1.0 + 3e-3, "smooth plastic at {wo}: albedo {a}");
        let mut rough = rough_plastic(Distribution::Ggx, 0.3);
        if let Bxdf::RoughPlasticDiffuse(b) = &mut rough[1] {
            b.d = Color::ONE / ((1.0 - b.table.internal_reflectance) * PLASTIC_ETA * PLASTIC_ETA);
        }
        let a = albedo(&bsdf_of(&rough, wo), wo, 200_000, Transport::Radiance);
        assert!(a.max_element() <= 1.0 + 3e-3, "rough plastic at {wo}: albedo {a}");
    }
    // A smooth conductor reflects F, a dielectric with scales reflects and transmits them.
    let crate::material::conductors::ComplexIor { eta, k, .. } = crate::material::conductors::lookup("Au").unwrap();
    let gold = bsdf_of(&[Bxdf::Conductor(Conductor { eta, k, measured: None, scale: Color::ONE })], Vec3::Z);
    let s = gold.sample(Vec3::Z, 0.5, crate::math::Vec2::splat(0.5), Transport::Radiance).unwrap();
    assert!(s.weight.abs_diff_eq(Color::new(0.96668, 0.80201, 0.32412), 2e-4), "{}", s.weight);
    let tinted = Dielectric { eta: 1.5, r: Color::new(1.0, 0.5, 0.0), t: Color::new(0.0, 0.5, 1.0) };
    let a = albedo(&bsdf_of(&[Bxdf::Dielectric(tinted)], Vec3::Z), Vec3::Z, 100_000, Transport::Importance);
    assert!(a.abs_diff_eq(Color::new(0.04, 0.5, 0.96), 5e-3), "{a}");
}

#[test]
fn plastics_match_mitsubas_values() {
    // Mitsuba 3.9.1 roughplastic, GGX alpha 0.3, eta 1.48959: transmittance table and the
    // internal reflectance (the notes' numpy reproduction of its quadrature, matched to 1e-7).
    let (_, t) = coating(Distribution::Ggx, 0.3);
    assert!((t.transmittance[0] - 0.63604).abs() < 2e-4, "{}", t.transmittance[0]);
    assert!((t.transmittance[32] - 0.88998).abs() < 2e-4, "{}", t.transmittance[32]);
    assert!((t.transmittance[63] - 0.95454).abs() < 2e-4, "{}", t.transmittance[63]);
    assert!((t.internal_reflectance - 0.40876).abs() < 5e-4, "{}", t.internal_reflectance);
    // Smooth plastic, d = (0.2, 0.5, 0.8): the density of a diffuse direction is
    // (1 - P_spec) cos / pi with P_spec from the Fresnel reflectance and the weights 1 : 0.5.
    let wo = Vec3::new(0.6, 0.0, 0.8);
    let b = bsdf_of(
        &[
            Bxdf::FresnelMirror(FresnelMirror { eta: PLASTIC_ETA, scale: Color::ONE }),
            Bxdf::PlasticDiffuse(PlasticDiffuse { d: Color::new(0.2, 0.5, 0.8), eta: PLASTIC_ETA, d_mean: 0.5 }),
        ],
        wo,
    );
    let wi = Vec3::new(-0.3, 0.2, 0.9).normalize();
    let fi = crate::material::fresnel::fresnel_dielectric(wo.z, PLASTIC_ETA);
    let ws = 1.0 / 1.5;
    let p_spec = fi * ws / (fi * ws + (1.0 - fi) * (1.0 - ws));
    let expected = (1.0 - p_spec) * wi.z / std::f32::consts::PI;
    assert!((b.pdf(wo, wi, Transport::Radiance) - expected).abs() < 1e-6);
}

#[test]
fn rough_lobes_samples_carry_their_weight_and_density() {
    use super::tests::check_sample_weights;
    for wo in wos() {
        for (name, lobe) in rough_conductors() {
            check_sample_weights(&name, &bsdf_of(&[lobe], wo), wo, Transport::Radiance);
        }
        for (d, alpha) in [(Distribution::Ggx, 0.2), (Distribution::Beckmann, 0.4)] {
            let [coat, base] = rough_plastic(d, alpha);
            check_sample_weights("rough coating", &bsdf_of(&[coat], wo), wo, Transport::Radiance);
            check_sample_weights("rough plastic base", &bsdf_of(&[base], wo), wo, Transport::Radiance);
        }
        let base = PlasticDiffuse { d: Color::new(0.2, 0.5, 0.8), eta: PLASTIC_ETA, d_mean: 0.5 };
        check_sample_weights("plastic base", &bsdf_of(&[Bxdf::PlasticDiffuse(base)], wo), wo, Transport::Radiance);
        for eta in [1.5, 1.0 / 1.5] {
            let mf = Microfacet::new(Distribution::Ggx, 0.3, 0.3);
            let glass = Bxdf::RoughDielectric(RoughDielectric { mf, eta, r: Color::ONE, t: Color::ONE });
            for mode in [Transport::Radiance, Transport::Importance] {
                check_sample_weights("rough glass", &bsdf_of(&[glass], wo), wo, mode);
            }
        }
    }
}
