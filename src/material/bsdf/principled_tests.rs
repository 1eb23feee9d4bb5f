//! Mitsuba 3's `principled` and `principledthin` BSDFs: our lobes against Mitsuba 3.9.1's own values at 600
//! pairs of directions under ten parameter sets (tests/data/principled/values.csv, from
//! scripts/make_principled_values.py), chi-square of sampling against the density for each set
//! from outside and (with transmission) from inside, reciprocity of the reflection lobes, and
//! the white furnace where energy must be conserved.

use super::*;
use crate::material::{Param, Plain, Principled, PrincipledThin};
use crate::math::{Frame, Vec2, Vec3};
use crate::sampling::Rng32;
use crate::sampling::chi2::{Chi2Config, chi2_directions};
use crate::sampling::warp::uniform_sphere;
use crate::texture::TexPoint;

/// Chi-square tests run in this file (for the Sidak correction).
const TESTS: usize = 33;

/// The parameter sets of scripts/make_principled_values.py.
fn case(name: &str) -> Principled {
    let mut p = Principled::new();
    let c = |r: f32, g: f32, b: f32| Param::Const(Color::new(r, g, b));
    let f = Param::Const;
    match name {
        "defaults" => {}
        "metal_sheen_coat" => {
            p.base_color = c(0.8, 0.3, 0.2);
            (p.roughness, p.metallic, p.spec_tint) = (f(0.3), f(0.6), f(0.5));
            (p.sheen, p.sheen_tint, p.clearcoat, p.clearcoat_gloss) = (f(0.7), f(0.4), f(0.8), f(0.6));
        }
        "anisotropic" => {
            p.base_color = c(0.2, 0.5, 0.9);
            (p.roughness, p.anisotropic, p.metallic) = (f(0.4), f(0.7), f(0.2));
        }
        "glass" => {
            p.base_color = c(0.9, 0.8, 0.7);
            (p.roughness, p.spec_trans, p.eta) = (f(0.2), f(0.8), 1.33);
        }
        "flat_sheen" => {
            p.base_color = c(0.3, 0.6, 0.3);
            (p.roughness, p.flatness, p.sheen) = (f(0.7), f(0.6), f(0.3));
            p.eta = Principled::eta_of_specular(0.8);
        }
        "polished_metal" => {
            p.base_color = c(0.95, 0.64, 0.54);
            (p.roughness, p.metallic) = (f(0.05), f(1.0));
        }
        "everything" => {
            p.base_color = c(0.6, 0.4, 0.7);
            (p.roughness, p.anisotropic, p.metallic, p.spec_trans) = (f(0.35), f(0.3), f(0.3), f(0.4));
            (p.spec_tint, p.sheen, p.sheen_tint) = (f(0.3), f(0.5), f(0.6));
            (p.clearcoat, p.clearcoat_gloss) = (f(0.5), f(0.2));
            p.eta = Principled::eta_of_specular(0.6);
        }
        other => panic!("unknown case {other}"),
    }
    p
}

/// The thin parameter sets of scripts/make_principled_values.py.
fn thin_case(name: &str) -> PrincipledThin {
    let mut p = PrincipledThin::default();
    let c = |r: f32, g: f32, b: f32| Param::Const(Color::new(r, g, b));
    let f = Param::Const;
    match name {
        "thin_defaults" => {}
        "thin_leaf" => {
            p.base_color = c(0.3, 0.7, 0.2);
            (p.roughness, p.spec_trans, p.diff_trans) = (f(0.4), f(0.3), f(0.8));
            (p.sheen, p.sheen_tint, p.flatness, p.eta) = (f(0.4), f(0.5), f(0.3), f(1.4));
        }
        "thin_glassy" => {
            p.base_color = c(0.9, 0.85, 0.8);
            (p.roughness, p.spec_trans, p.spec_tint, p.anisotropic, p.eta) =
                (f(0.15), f(0.85), f(0.4), f(0.5), f(1.33));
        }
        other => panic!("unknown case {other}"),
    }
    p
}

const THIN_CASES: [&str; 3] = ["thin_defaults", "thin_leaf", "thin_glassy"];

fn plain(name: &str) -> Plain {
    if name.starts_with("thin_") { Plain::PrincipledThin(thin_case(name)) } else { Plain::Principled(case(name)) }
}

const CASES: [&str; 7] =
    ["defaults", "metal_sheen_coat", "anisotropic", "glass", "flat_sheen", "polished_metal", "everything"];

fn lobes(p: &Plain, front: bool) -> Lobes {
    p.lobes(front, TexPoint::uv(Vec2::ZERO), &[], &crate::material::GivenSpectra::NONE)
}

/// The BSDF in the frame z = normal, seen from `wo`: our `Bsdf` picks the side.
fn bsdf(p: &Plain, wo: Vec3) -> Bsdf<'static> {
    let front = front_side(wo, Vec3::Z);
    Bsdf::new(Frame::from_z(Vec3::Z), Vec3::Z, front, lobes(p, front))
}

/// Mitsuba's `eval` (f times |cos| of the light's direction) for viewer direction `wi` and
/// light direction `wo`, in Mitsuba's names.
fn ours(p: &Plain, wi: Vec3, wo: Vec3) -> Color {
    let b = bsdf(p, wi);
    b.f(wi, wo, Transport::Radiance) * wo.z.abs()
}

#[test]
fn values_match_mitsubas() {
    let text =
        std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/principled/values.csv")).unwrap();
    let mut checked = 0;
    for line in text.lines().skip(1) {
        let cells: Vec<&str> = line.split(',').collect();
        let num = |i: usize| cells[i].parse::<f32>().unwrap();
        let p = plain(cells[0]);
        let wi = Vec3::new(num(2), num(3), num(4));
        let wo = Vec3::new(num(5), num(6), num(7));
        let want = Color::new(num(8), num(9), num(10));
        let got = ours(&p, wi, wo);
        let err = (got - want).abs().max_element();
        assert!(err <= 2e-3 * want.max_element() + 1e-5, "{}: wi {wi} wo {wo}: ours {got}, Mitsuba {want}", cells[0]);
        checked += usize::from(want.max_element() > 0.0);
    }
    assert!(checked > 400, "only {checked} non-zero values checked");
}

fn chi2(name: &str, b: &Bsdf, wo: Vec3, mode: Transport) {
    let config = Chi2Config { tests: TESTS, samples: 300_000, ..Chi2Config::with_theta_res(16) };
    chi2_directions(
        name,
        |u, uc| b.sample(wo, uc, u, mode).filter(|s| !s.flags.is_specular()).map(|s| s.wi),
        |wi| b.pdf(wo, wi, mode),
        &config,
    )
    .unwrap_or_else(|report| panic!("{report}"));
}

#[test]
fn sampling_matches_the_density_outside_and_inside() {
    let wos = [Vec3::new(0.3, 0.1, 0.95).normalize(), Vec3::new(-0.8, 0.3, 0.3).normalize()];
    for name in CASES.iter().chain(&THIN_CASES) {
        let p = plain(name);
        for wo in wos {
            chi2(&format!("principled {name} wo {wo}"), &bsdf(&p, wo), wo, Transport::Radiance);
        }
        if ["glass", "everything", "thin_leaf"].contains(name) {
            let wo = -wos[0];
            chi2(&format!("principled {name} inside"), &bsdf(&p, wo), wo, Transport::Importance);
        }
    }
}

#[test]
fn reflection_is_reciprocal() {
    let mut rng = Rng32::new(3);
    for name in CASES.iter().chain(&THIN_CASES) {
        let b = lobes(&plain(name), true);
        for _ in 0..2000 {
            let (a, c) = (uniform_sphere(rng.uniform2()), uniform_sphere(rng.uniform2()));
            let (a, c) = (Vec3::new(a.x, a.y, a.z.abs()), Vec3::new(c.x, c.y, c.z.abs()));
            for lobe in b
                .as_slice()
                .iter()
                .filter(|l| !l.flags().is_transmission() || l.flags().contains(LobeFlags::GLOSSY_REFLECTION))
            {
                let (fac, fca) = (lobe.f(a, c, Transport::Radiance), lobe.f(c, a, Transport::Radiance));
                assert!(
                    (fac - fca).abs().max_element() <= 1e-4 * fac.max_element().max(1.0),
                    "{name} {lobe:?}: {fac} vs {fca}"
                );
            }
        }
    }
}

/// Mean sample weight from `wo`: the directional albedo.
fn albedo(b: &Bsdf, wo: Vec3, n: usize) -> Color {
    let mut rng = Rng32::new(29);
    let mut sum = Color::ZERO;
    for _ in 0..n {
        if let Some(s) = b.sample(wo, rng.uniform(), rng.uniform2(), Transport::Importance) {
            sum += s.weight;
        }
    }
    sum / n as f32
}

/// A white metal only loses energy (single scattering, Schlick F <= 1), and keeps most of it
/// when polished; a smooth white dielectric lobe (reflection plus refraction, no base tint)
/// seen from inside keeps what Fresnel does not trap. Burley's diffuse is not energy
/// conserving (its retro-reflection gains at grazing angles) and is not held to 1.
#[test]
fn white_furnace() {
    let mut metal = Principled::new();
    (metal.base_color, metal.metallic) = (Param::Const(Color::ONE), Param::Const(1.0));
    for (roughness, at_least) in [(0.05, 0.97), (0.5, 0.8)] {
        metal.roughness = Param::Const(roughness);
        for wo in [Vec3::Z, Vec3::new(0.6, 0.0, 0.8)] {
            let a = albedo(&bsdf(&Plain::Principled(metal), wo), wo, 200_000);
            assert!(a.max_element() <= 1.0 + 2e-3 && a.min_element() >= at_least, "metal r {roughness} at {wo}: {a}");
        }
    }
    let mut glass = Principled::new();
    (glass.base_color, glass.spec_trans, glass.roughness) =
        (Param::Const(Color::ONE), Param::Const(1.0), Param::Const(0.05));
    for wo in [Vec3::Z, Vec3::new(0.6, 0.0, 0.8)] {
        let a = albedo(&bsdf(&Plain::Principled(glass), wo), wo, 200_000);
        assert!(a.max_element() <= 1.0 + 2e-3 && a.min_element() >= 0.97, "glass at {wo}: {a}");
        let inside = -wo;
        let a = albedo(&bsdf(&Plain::Principled(glass), inside), inside, 200_000);
        assert!(a.max_element() <= 1.0 + 2e-3 && a.min_element() >= 0.97, "glass from inside at {wo}: {a}");
    }
}

#[test]
fn each_principled_lobe_sample_carries_its_weight_and_density() {
    use super::tests::check_sample_weights;
    for name in CASES.iter().chain(&THIN_CASES) {
        let p = plain(name);
        for wo in [Vec3::new(0.3, -0.2, 0.9).normalize(), Vec3::new(-0.8, 0.1, 0.3).normalize()] {
            for lobe in lobes(&p, true).as_slice() {
                if lobe.flags().is_specular() {
                    continue;
                }
                let mut one = Lobes::default();
                one.add(*lobe);
                let b = Bsdf::new(Frame::from_z(Vec3::Z), Vec3::Z, true, one);
                check_sample_weights(&format!("{name} {lobe:?}"), &b, wo, Transport::Radiance);
            }
        }
    }
}
