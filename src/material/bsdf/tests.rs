//! Tests of every lobe and of the mixtures materials make: sampling against the density
//! (chi-square over a (theta, phi) grid, pbrt-v4 style; for delta lobes, over their discrete
//! choices), reciprocity of reflection, and the white furnace (directional albedo at most 1).

use super::*;
use crate::material::bxdf::{Dielectric, Lambert, Mirror, Phong, Transmission};
use crate::material::fresnel::fresnel_dielectric;
use crate::material::{Classic, ClassicKind};
use crate::math::{Frame, Vec3};
use crate::sampling::Rng32;
use crate::sampling::chi2::{Chi2Config, chi2_directions, chi2_p_value};
use crate::sampling::warp::uniform_sphere;

/// Chi-square tests run in this file (for the Sidak correction).
const TESTS: usize = 14;

fn single(lobe: Bxdf, wo: Vec3) -> Bsdf<'static> {
    let mut lobes = Lobes::default();
    lobes.add(lobe);
    Bsdf::new(Frame::from_z(Vec3::Z), Vec3::Z, front_side(wo, Vec3::Z), lobes)
}

fn classic(kind: ClassicKind, kd: f32, ks: f32, kr: f32, kt: f32, wo: Vec3) -> Bsdf<'static> {
    let m = Classic { kind, color: Color::new(0.9, 0.6, 0.3), kd, ks, kr, kt, exponent: 20.0, ..Classic::default() };
    let hit = crate::geometry::Hit {
        t: 1.0,
        p: Vec3::ZERO,
        p_error: Vec3::ZERO,
        ng: Vec3::Z,
        ns: Vec3::Z,
        param: crate::geometry::SurfaceParam::Known { uv: crate::math::Vec2::ZERO, dpdu: Vec3::X, dpdv: Vec3::Y },
        material: 0,
        light: crate::geometry::NO_LIGHT,
        prim: 0,
    };
    let front = front_side(wo, hit.ng);
    Bsdf::new(hit.shading_frame(), hit.ng, front, m.lobes(front))
}

fn wos() -> [Vec3; 3] {
    [Vec3::Z, Vec3::new(0.5, 0.2, 0.8).normalize(), Vec3::new(-0.9, 0.1, 0.25).normalize()]
}

/// Chi-square of `sample` (non-delta samples) against `pdf` for one BSDF and `wo`.
fn chi2_bsdf(name: &str, b: &Bsdf, wo: Vec3, mode: Transport) {
    let config = Chi2Config { tests: TESTS, samples: 400_000, ..Chi2Config::default() };
    chi2_directions(
        name,
        |u, uc| b.sample(wo, uc, u, mode).filter(|s| !s.flags.is_specular()).map(|s| s.wi),
        |wi| b.pdf(wo, wi, mode),
        &config,
    )
    .unwrap_or_else(|report| panic!("{report}"));
}

#[test]
fn lambert_sampling_matches_its_pdf() {
    for wo in wos() {
        chi2_bsdf("lambert", &single(Bxdf::Lambert(Lambert { r: Color::splat(0.7) }), wo), wo, Transport::Radiance);
    }
}

#[test]
fn phong_sampling_matches_its_pdf() {
    for (wo, n) in wos().into_iter().zip([1.0, 20.0, 200.0]) {
        let b = single(Bxdf::Phong(Phong { ks: 0.8, exponent: n }), wo);
        chi2_bsdf(&format!("phong n={n}"), &b, wo, Transport::Radiance);
    }
}

#[test]
fn classic_mixtures_sample_their_pdf() {
    // Diffuse + glossy + mirror: the non-delta part's samples follow the mixture density.
    for wo in wos() {
        let b = classic(ClassicKind::Reflective, 0.5, 0.3, 0.2, 0.0, wo);
        chi2_bsdf("diffuse + phong + mirror", &b, wo, Transport::Importance);
    }
}

/// Chi-square over discrete outcomes with expected probabilities `p` (their sum may be below 1:
/// the rest is absorption / failed samples, counted in an extra cell).
fn chi2_discrete(name: &str, counts: &[u64], p: &[f64], n: u64) {
    let mut cells: Vec<(f64, f64)> = counts.iter().zip(p).map(|(&c, &q)| (c as f64, q * n as f64)).collect();
    let rest_p = 1.0 - p.iter().sum::<f64>();
    let rest_c = n - counts.iter().sum::<u64>();
    cells.push((rest_c as f64, rest_p.max(0.0) * n as f64));
    let used: Vec<&(f64, f64)> = cells.iter().filter(|c| c.1 >= 5.0).collect();
    for c in cells.iter().filter(|c| c.1 < 5.0) {
        assert!(c.0 <= 5.0 + 3.0 * c.1.sqrt(), "{name}: {} samples where {} were expected", c.0, c.1);
    }
    let stat: f64 = used.iter().map(|(o, e)| (o - e) * (o - e) / e).sum();
    let p_value = chi2_p_value(stat, used.len().saturating_sub(1).max(1));
    let alpha = 1.0 - (1.0f64 - 0.01).powf(1.0 / TESTS as f64);
    assert!(p_value >= alpha, "{name}: counts {counts:?} for probabilities {p:?} (n {n}): p-value {p_value}");
}

#[test]
fn delta_lobes_pick_their_directions_with_the_right_probabilities() {
    let mut rng = Rng32::new(5);
    let n = 200_000u64;
    for wo in wos() {
        // Mirror: always the reflected direction, weight = reflectance.
        let b = single(Bxdf::Mirror(Mirror { r: Color::new(0.9, 0.5, 0.2) }), wo);
        let s = b.sample(wo, rng.uniform(), rng.uniform2(), Transport::Radiance).unwrap();
        assert!(s.wi.abs_diff_eq(Vec3::new(-wo.x, -wo.y, wo.z), 1e-6) && s.flags.is_specular());
        assert!(s.weight.abs_diff_eq(Color::new(0.9, 0.5, 0.2), 1e-6));
        // Dielectric: reflection with probability F, refraction otherwise; both weights 1 in
        // importance mode.
        for eta in [1.5, 1.0 / 1.5] {
            let b = single(Bxdf::Dielectric(Dielectric::clear(eta)), wo);
            let f = fresnel_dielectric(wo.z, eta) as f64;
            let mut counts = [0u64; 2];
            for _ in 0..n {
                let Some(s) = b.sample(wo, rng.uniform(), rng.uniform2(), Transport::Importance) else { continue };
                assert!((s.weight - Color::ONE).abs().max_element() < 1e-5, "{}", s.weight);
                counts[usize::from(s.flags.is_transmission())] += 1;
            }
            chi2_discrete(&format!("dielectric eta {eta}"), &counts, &[f, 1.0 - f], n);
        }
        // The seed's transparent material: mirror k_r and fixed transmission k_t, picked by weight.
        let b = classic(ClassicKind::Transparent, 0.0, 0.0, 0.3, 0.6, wo);
        let mut counts = [0u64; 2];
        for _ in 0..n {
            let Some(s) = b.sample(wo, rng.uniform(), rng.uniform2(), Transport::Importance) else { continue };
            counts[usize::from(s.flags.is_transmission())] += 1;
        }
        chi2_discrete("transparent", &counts, &[1.0 / 3.0, 2.0 / 3.0], n);
        let t = single(Bxdf::Transmission(Transmission { t: 0.6, eta: 1.5 }), wo);
        let s = t.sample(wo, 0.5, rng.uniform2(), Transport::Radiance).unwrap();
        assert!((s.weight.r() - 0.6 / 2.25).abs() < 1e-6, "radiance through glass is scaled by 1/eta^2");
    }
}

#[test]
fn reflection_lobes_are_reciprocal() {
    let mut rng = Rng32::new(9);
    let lobes =
        [Bxdf::Lambert(Lambert { r: Color::new(0.7, 0.4, 0.2) }), Bxdf::Phong(Phong { ks: 0.6, exponent: 30.0 })];
    for _ in 0..2000 {
        let (a, b) = (uniform_sphere(rng.uniform2()), uniform_sphere(rng.uniform2()));
        let (a, b) = (Vec3::new(a.x, a.y, a.z.abs()), Vec3::new(b.x, b.y, b.z.abs()));
        for lobe in lobes {
            let (fab, fba) = (lobe.f(a, b, Transport::Radiance), lobe.f(b, a, Transport::Radiance));
            assert!((fab - fba).abs().max_element() <= 1e-5 * fab.max_element().max(1.0), "{lobe:?}: {fab} vs {fba}");
        }
        // The classic mixture as a whole.
        let m = classic(ClassicKind::Reflective, 0.5, 0.3, 0.2, 0.0, a);
        let (fab, fba) = (m.f(a, b, Transport::Radiance), m.f(b, a, Transport::Radiance));
        assert!((fab - fba).abs().max_element() <= 1e-5 * fab.max_element().max(1.0));
    }
}

/// Monte Carlo directional albedo: the mean weight of `n` samples, per channel.
fn albedo(b: &Bsdf, wo: Vec3, n: usize, mode: Transport, photon: bool) -> Color {
    let mut rng = Rng32::new(17);
    let mut sum = Color::ZERO;
    for _ in 0..n {
        let s = if photon {
            b.sample_lobe(wo, rng.uniform(), rng.uniform2(), mode)
        } else {
            b.sample(wo, rng.uniform(), rng.uniform2(), mode)
        };
        if let Some(s) = s {
            sum += s.weight;
        }
    }
    sum / n as f32
}

#[test]
fn white_furnace_albedo_is_at_most_one() {
    let lobes = [
        Bxdf::Lambert(Lambert { r: Color::ONE }),
        Bxdf::Phong(Phong { ks: 1.0, exponent: 1.0 }),
        Bxdf::Phong(Phong { ks: 1.0, exponent: 50.0 }),
        Bxdf::Mirror(Mirror { r: Color::ONE }),
        Bxdf::Transmission(Transmission { t: 1.0, eta: 1.5 }),
        Bxdf::Dielectric(Dielectric::clear(1.5)),
        Bxdf::Dielectric(Dielectric::clear(1.0 / 1.5)),
    ];
    for wo in wos() {
        for lobe in lobes {
            let b = single(lobe, wo);
            for photon in [false, true] {
                let a = albedo(&b, wo, 100_000, Transport::Importance, photon);
                assert!(a.max_element() <= 1.0 + 1e-3, "{lobe:?} at {wo}: albedo {a}");
                // The lossless lobes keep everything: a white Lambert, a mirror and a smooth
                // dielectric (reflection plus transmission, total internal reflection included).
                if matches!(lobe, Bxdf::Lambert(_) | Bxdf::Mirror(_) | Bxdf::Dielectric(_)) {
                    assert!(a.min_element() >= 1.0 - 1e-3, "{lobe:?} at {wo}: albedo {a}, expected 1");
                }
            }
        }
        // Over-bright classic materials are scaled so the sum of their lobes is at most one.
        let b = classic(ClassicKind::Transparent, 0.9, 0.7, 0.5, 0.5, wo);
        let a = albedo(&b, wo, 100_000, Transport::Importance, false);
        assert!(a.max_element() <= 1.0 + 0.01, "{a}");
    }
}

#[test]
fn lambert_albedo_is_its_reflectance() {
    let wo = Vec3::new(0.3, 0.2, 0.9).normalize();
    let b = classic(ClassicKind::Diffuse, 0.7, 0.0, 0.0, 0.0, wo);
    let a = albedo(&b, wo, 50_000, Transport::Radiance, false);
    assert!((a - Color::new(0.9, 0.6, 0.3) * 0.7).abs().max_element() < 1e-3, "{a}");
}

#[test]
fn dielectric_reflects_and_transmits_by_fresnel() {
    let m = Classic { kind: ClassicKind::Dielectric, kd: 0.0, ks: 0.0, ior: 1.5, ..Classic::default() };
    let b = classic_material(&m, Vec3::Z);
    let mut rng = Rng32::new(1);
    let (mut refl, mut trans, n) = (0.0, 0.0, 100_000);
    for _ in 0..n {
        let s = b.sample(Vec3::Z, rng.uniform(), rng.uniform2(), Transport::Importance).unwrap();
        if s.flags.is_transmission() {
            trans += s.weight.r();
        } else {
            refl += s.weight.r();
        }
    }
    assert!((refl / n as f32 - 0.04).abs() < 1e-3 && (trans / n as f32 - 0.96).abs() < 1e-3);
    // In radiance mode the transmitted weight carries 1/eta^2.
    let s = (0..100).find_map(|_| {
        let s = b.sample(Vec3::Z, rng.uniform(), rng.uniform2(), Transport::Radiance)?;
        s.flags.is_transmission().then_some(s)
    });
    assert!((s.unwrap().weight.r() - 1.0 / 2.25).abs() < 1e-4);
}

#[test]
fn a_dielectric_splits_into_its_fresnel_weighted_directions() {
    for wo in wos() {
        for eta in [1.5f32, 1.0 / 1.5, 1.33] {
            let glass = Dielectric { eta, r: Color::new(0.9, 0.8, 0.7), t: Color::new(0.6, 0.7, 0.8) };
            let b = single(Bxdf::Dielectric(glass), wo);
            for mode in [Transport::Radiance, Transport::Importance] {
                let [a, t] = b.dielectric_split(wo, mode).expect("one dielectric lobe splits");
                let f = fresnel_dielectric(wo.z, eta);
                let scale = if mode == Transport::Radiance { 1.0 / (eta * eta) } else { 1.0 };
                if f >= 1.0 {
                    // Total internal reflection: reflection alone, with the whole weight.
                    let a = a.expect("reflection");
                    assert!(t.is_none() && a.weight.abs_diff_eq(glass.r, 1e-6));
                    continue;
                }
                let (a, t) = (a.expect("reflection"), t.expect("refraction"));
                assert!(a.wi.abs_diff_eq(Vec3::new(-wo.x, -wo.y, wo.z), 1e-6) && !a.flags.is_transmission());
                assert!(a.weight.abs_diff_eq(glass.r * f, 1e-6), "{} vs F r {}", a.weight, glass.r * f);
                assert!(t.flags.is_transmission() && t.wi.z * wo.z < 0.0);
                assert!(t.weight.abs_diff_eq(glass.t * ((1.0 - f) * scale), 1e-6), "{}", t.weight);
                // Snell: the tangential parts scale by 1 / eta.
                let tangential = |v: Vec3| (v.x * v.x + v.y * v.y).sqrt();
                assert!((tangential(t.wi) - tangential(wo) / eta).abs() < 1e-5);
                // The split is the mean of the one-sample choice.
                let mut rng = Rng32::new(3);
                let n = 200_000;
                let mut mean = Color::ZERO;
                for _ in 0..n {
                    mean += b.sample(wo, rng.uniform(), rng.uniform2(), mode).map_or(Color::ZERO, |s| s.weight);
                }
                mean /= n as f32;
                let split = a.weight + t.weight;
                assert!((mean - split).abs().max_element() < 3e-3, "{mean} vs {split}");
            }
        }
        // Grazing from inside dense glass: total internal reflection.
        let inside = Vec3::new(0.95, 0.0, (1.0f32 - 0.95 * 0.95).sqrt());
        let b = single(Bxdf::Dielectric(Dielectric::clear(1.0 / 1.5)), inside);
        let [a, t] = b.dielectric_split(inside, Transport::Radiance).unwrap();
        assert!(t.is_none() && a.is_some_and(|a| a.weight.abs_diff_eq(Color::ONE, 1e-6)));
        // Anything but one dielectric lobe does not split.
        let mirror = single(Bxdf::Mirror(Mirror { r: Color::ONE }), wo);
        assert!(mirror.dielectric_split(wo, Transport::Radiance).is_none());
        let transparent = classic(ClassicKind::Transparent, 0.0, 0.0, 0.3, 0.6, wo);
        assert!(transparent.dielectric_split(wo, Transport::Radiance).is_none());
    }
}

fn classic_material(m: &Classic, wo: Vec3) -> Bsdf<'static> {
    let hit = crate::geometry::Hit {
        t: 1.0,
        p: Vec3::ZERO,
        p_error: Vec3::ZERO,
        ng: Vec3::Z,
        ns: Vec3::Z,
        param: crate::geometry::SurfaceParam::Known { uv: crate::math::Vec2::ZERO, dpdu: Vec3::X, dpdv: Vec3::Y },
        material: 0,
        light: crate::geometry::NO_LIGHT,
        prim: 0,
    };
    let front = front_side(wo, hit.ng);
    Bsdf::new(hit.shading_frame(), hit.ng, front, m.lobes(front))
}

/// The seed report's `transparent` kind under total internal reflection: the share k_t that
/// cannot leave the denser medium is reflected (as the Whitted integrator does), not lost.
#[test]
fn fixed_transmission_reflects_under_total_internal_reflection() {
    use crate::material::bxdf::Transmission;
    // Inside glass (eta = 1 / 1.5 seen from inside) at 60 degrees, beyond the critical angle.
    let wo = Vec3::new(60f32.to_radians().sin(), 0.0, 60f32.to_radians().cos());
    let s = Bxdf::Transmission(Transmission { t: 0.7, eta: 1.0 / 1.5 })
        .sample(wo, 0.5, Vec2::splat(0.5), Transport::Radiance)
        .expect("reflected");
    assert!((s.wi - Vec3::new(-wo.x, -wo.y, wo.z)).length() < 1e-6, "{}", s.wi);
    assert_eq!(s.weight, Color::splat(0.7));
    assert!(s.flags.is_specular() && !s.flags.is_transmission());
    // Below the critical angle it refracts as before.
    let wo = Vec3::new(20f32.to_radians().sin(), 0.0, 20f32.to_radians().cos());
    let s = Bxdf::Transmission(Transmission { t: 0.7, eta: 1.0 / 1.5 })
        .sample(wo, 0.5, Vec2::splat(0.5), Transport::Radiance)
        .unwrap();
    assert!(s.flags.is_transmission() && s.wi.z < 0.0);
}

/// Photons on a smooth-shaded surface (shading normal tilted from the geometric one) scatter
/// with Veach's adjoint BSDF: on average a photon arriving from `wo` leaves a Lambertian surface
/// with weight (rho / pi) |wo.ns| / |wo.ng| times the integral of |wi.ng| over the shading
/// hemisphere above the geometric surface, which the path tracer's light transport implies; the
/// plain BSDF gives rho times the share of that hemisphere above the surface.
#[test]
fn photons_scatter_with_the_adjoint_bsdf_under_shading_normals() {
    use crate::material::bxdf::Lambert;
    let ns = Vec3::new(0.35, 0.0, 1.0).normalize();
    let mut lobes = Lobes::default();
    lobes.add(Bxdf::Lambert(Lambert { r: Color::splat(0.6) }));
    let bsdf = Bsdf::new(Frame::from_z(ns), Vec3::Z, true, lobes);
    let wo = Vec3::new(-0.6, 0.2, 0.5).normalize();
    let mut rng = crate::sampling::Rng32::new(17);
    let n = 400_000;
    let mut mean = 0.0f64;
    for _ in 0..n {
        if let Some(s) = bsdf.sample_lobe(wo, rng.uniform(), rng.uniform2(), Transport::Importance) {
            mean += s.weight.r() as f64;
        }
    }
    mean /= n as f64;
    // Integral of |wi.ng| over the hemisphere around ns, by the midpoint rule in spherical
    // coordinates about ns.
    let frame = Frame::from_z(ns);
    let (nt, np) = (400, 800);
    let mut integral = 0.0f64;
    for i in 0..nt {
        let t = (i as f64 + 0.5) / nt as f64 * std::f64::consts::FRAC_PI_2;
        for j in 0..np {
            let p = (j as f64 + 0.5) / np as f64 * 2.0 * std::f64::consts::PI;
            let local = Vec3::new((t.sin() * p.cos()) as f32, (t.sin() * p.sin()) as f32, t.cos() as f32);
            let wi = frame.to_world(local);
            // Directions below the geometric surface are refused (light would leak through it).
            integral += (wi.z as f64).max(0.0)
                * t.sin()
                * (std::f64::consts::FRAC_PI_2 / nt as f64)
                * (2.0 * std::f64::consts::PI / np as f64);
        }
    }
    let expected = 0.6 / std::f64::consts::PI * (wo.dot(ns) as f64).abs() / (wo.z as f64).abs() * integral;
    assert!((mean - expected).abs() < 0.005 * expected, "mean weight {mean}, expected {expected}");
}

/// Checks the sampling contract one BSDF keeps for `wo`: every non-delta sample's weight is
/// f |cos| / pdf and its density is `pdf`, as `eval` gives them (the path tracer takes a
/// one-lobe BSDF's sample as it comes, without evaluating the mixture), and `eval` is `f` and
/// `pdf` bit for bit.
pub(super) fn check_sample_weights(name: &str, b: &Bsdf, wo: Vec3, mode: Transport) {
    let mut rng = Rng32::new(0x5eed);
    let mut checked = 0;
    for _ in 0..4000 {
        let Some(s) = b.sample(wo, rng.uniform(), rng.uniform2(), mode) else { continue };
        if s.flags.is_specular() {
            continue;
        }
        let (f, pdf) = b.eval(wo, s.wi, mode);
        assert_eq!((f, pdf), (b.f(wo, s.wi, mode), b.pdf(wo, s.wi, mode)), "{name}: eval is not f and pdf");
        assert!((s.pdf - pdf).abs() <= 1e-3 * pdf, "{name}: wo {wo} wi {}: sampled pdf {} vs {pdf}", s.wi, s.pdf);
        let want = f * (s.wi.dot(b.normal()).abs() / pdf);
        let err = (s.weight - want).abs().max_element();
        assert!(
            err <= 2e-3 * want.max_element() + 1e-6,
            "{name}: wo {wo} wi {}: weight {} vs f|cos|/pdf {want}",
            s.wi,
            s.weight
        );
        checked += 1;
    }
    assert!(checked > 100, "{name}: only {checked} non-delta samples");
}

#[test]
fn lambert_and_phong_samples_carry_their_weight_and_density() {
    for wo in wos() {
        check_sample_weights(
            "lambert",
            &single(Bxdf::Lambert(Lambert { r: Color::new(0.7, 0.2, 0.4) }), wo),
            wo,
            Transport::Radiance,
        );
        for n in [1.0, 20.0] {
            check_sample_weights(
                "phong",
                &single(Bxdf::Phong(Phong { ks: 0.8, exponent: n }), wo),
                wo,
                Transport::Radiance,
            );
        }
    }
}

/// A bump or normal map's shadow-terminator term belongs to the direction light arrives from:
/// importance transport (light paths, photons) evaluates the adjoint, f(wo, wi, Importance) =
/// f(wi, wo, Radiance), and samples and densities follow it in each mode.
#[test]
fn perturbed_normals_give_the_adjoint_in_importance_transport() {
    use crate::material::bxdf::{Lambert, Phong};
    let mut lobes = Lobes::default();
    lobes.add(Bxdf::Lambert(Lambert { r: Color::splat(0.5) }));
    lobes.add(Bxdf::Phong(Phong { ks: 0.4, exponent: 12.0 }));
    let tilted = Frame::from_z(Vec3::new(0.45, -0.2, 1.0).normalize());
    let bsdf = Bsdf::new(Frame::from_z(Vec3::Z), Vec3::Z, true, lobes).perturbed(tilted);
    let mut rng = Rng32::new(21);
    let mut compared = 0;
    for _ in 0..4000 {
        let (a, b) = (uniform_sphere(rng.uniform2()), uniform_sphere(rng.uniform2()));
        let (a, b) = (Vec3::new(a.x, a.y, a.z.abs()), Vec3::new(b.x, b.y, b.z.abs()));
        // Pairs above the perturbed surface too, where the lobes are reciprocal (below it they
        // check only `wi`'s side).
        if a.dot(tilted.z) <= 0.0 || b.dot(tilted.z) <= 0.0 {
            continue;
        }
        let (imp, rad) = (bsdf.f(a, b, Transport::Importance), bsdf.f(b, a, Transport::Radiance));
        assert!((imp - rad).abs().max_element() <= 1e-5 * rad.max_element().max(1e-3), "{a} {b}: {imp} vs {rad}");
        compared += usize::from(rad != Color::ZERO && bsdf.f(a, b, Transport::Radiance) != rad);
    }
    // The term differs between the two directions of most pairs: the check compares something.
    assert!(compared > 500, "only {compared} pairs where the direction matters");
    for wo in wos().into_iter().filter(|w| w.z > 0.3) {
        for mode in [Transport::Radiance, Transport::Importance] {
            chi2_bsdf(&format!("perturbed {mode:?}"), &bsdf, wo, mode);
            check_sample_weights("perturbed", &bsdf, wo, mode);
        }
    }
}

#[test]
fn one_lambert_evaluates_as_the_lobes_bit_for_bit() {
    let mut rng = Rng32::new(11);
    for trial in 0..200 {
        // Tilted shading frames (a shading normal off the geometric one), both sides, opacity.
        let ns = (Vec3::Z + 0.4 * uniform_sphere(rng.uniform2())).normalize();
        let wo = uniform_sphere(rng.uniform2());
        let mut lobes = Lobes::default();
        lobes.add(Bxdf::Lambert(Lambert { r: Color::new(0.8, 0.5 * rng.uniform(), 0.2) }));
        let mut b = Bsdf::new(Frame::from_z(ns), Vec3::Z, front_side(wo, Vec3::Z), lobes);
        if trial % 2 == 1 {
            b = b.with_opacity(rng.uniform());
        }
        let one = b.one_lambert().expect("one Lambertian lobe");
        for _ in 0..50 {
            let wi = uniform_sphere(rng.uniform2());
            for mode in [Transport::Radiance, Transport::Importance] {
                let bits = |(f, pdf): (Color, f32)| (f.to_array().map(f32::to_bits), pdf.to_bits());
                let lobes = b.eval_lobes(wo, wi, mode);
                assert_eq!(bits(lobes), bits(one.eval(wi)), "wo {wo} wi {wi}");
                assert_eq!(bits(lobes), bits(b.eval(wo, wi, mode)));
                assert_eq!(bits((b.f_lobes(wo, wi, mode), b.pdf_lobes(wo, wi, mode))), bits(lobes));
                assert_eq!(bits((b.f(wo, wi, mode), b.pdf(wo, wi, mode))), bits(lobes));
            }
        }
    }
    // Sampling, opaque: the same samples as the lobe loop.
    for _ in 0..200 {
        let ns = (Vec3::Z + 0.4 * uniform_sphere(rng.uniform2())).normalize();
        let wo = uniform_sphere(rng.uniform2());
        let mut lobes = Lobes::default();
        lobes.add(Bxdf::Lambert(Lambert { r: Color::new(0.8, 0.5, 0.2) }));
        let b = Bsdf::new(Frame::from_z(ns), Vec3::Z, front_side(wo, Vec3::Z), lobes);
        for _ in 0..50 {
            let (uc, u) = (rng.uniform(), rng.uniform2());
            let bits = |s: Option<BsdfSample>| {
                s.map(|s| {
                    (s.wi.to_array().map(f32::to_bits), s.weight.to_array().map(f32::to_bits), s.pdf.to_bits(), s.flags)
                })
            };
            for mode in [Transport::Radiance, Transport::Importance] {
                let lobes = b.sample_lobes(wo, uc, u, mode);
                assert_eq!(bits(b.sample(wo, uc, u, mode)), bits(lobes), "wo {wo} u {u}");
                let lobes = b.sample_lobe_lobes(wo, uc, u, mode);
                assert_eq!(bits(b.sample_lobe(wo, uc, u, mode)), bits(lobes), "photon: wo {wo} u {u}");
            }
        }
    }
    // Anything else is not one Lambertian lobe.
    assert!(classic(ClassicKind::Diffuse, 0.6, 0.3, 0.0, 0.0, Vec3::Z).one_lambert().is_none());
    assert!(single(Bxdf::Mirror(Mirror { r: Color::ONE }), Vec3::Z).one_lambert().is_none());
}
