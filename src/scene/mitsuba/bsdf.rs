//! Mitsuba BSDFs mapped onto caustic's materials (`docs/mitsuba.md` lists what maps exactly and
//! what is approximated, with a warning).

use super::Build;
use super::props::Cx;
use super::xml::El;
use crate::material::{Material, MaterialKind};
use crate::math::Color;
use crate::scene::SceneError;

/// Mitsuba's diffuse BSDF in our model: physical albedo kd x colour.
pub(super) fn diffuse(color: Color) -> Material {
    Material { kind: MaterialKind::Diffuse, color, ka: 0.0, kd: 1.0, ks: 0.0, ..Material::default() }
}

fn mirror(kr: f32) -> Material {
    Material { kind: MaterialKind::Reflective, color: Color::ONE, ka: 0.0, kd: 0.0, ks: 0.0, kr, ..Material::default() }
}

/// Fresnel reflectance at normal incidence for relative index `eta`.
fn f0(eta: f32) -> f32 {
    ((eta - 1.0) / (eta + 1.0)).powi(2)
}

impl<'a> Cx<'a> {
    /// Builds the material of a `<bsdf>` element (cached per element).
    pub(super) fn material(&mut self, el: &'a El, b: &mut Build) -> Result<u32, SceneError> {
        let key = el as *const El as usize;
        if let Some(&i) = b.bsdf_cache.get(&key) {
            return Ok(i);
        }
        let m = self.bsdf(el, 0)?;
        let name = match self.attr(el, "id")? {
            Some((id, _)) => id,
            None => format!("(bsdf {})", b.geometry.material_count() + 1),
        };
        let i = b.geometry.add_material(name, m);
        b.bsdf_cache.insert(key, i);
        Ok(i)
    }

    pub(super) fn default_material(&self, b: &mut Build) -> u32 {
        if let Some(i) = b.default_material {
            return i;
        }
        // Mitsuba's default BSDF: diffuse with reflectance 0.5.
        let i = b.geometry.add_material("(default diffuse)", diffuse(Color::splat(0.5)));
        b.default_material = Some(i);
        i
    }

    /// Maps a Mitsuba BSDF to our material.
    pub(super) fn bsdf(&mut self, el: &'a El, depth: usize) -> Result<Material, SceneError> {
        if depth > 8 {
            return Err(self.err(el, "BSDFs nested too deeply"));
        }
        let p = self.props(el)?;
        let m = match p.kind.as_str() {
            "diffuse" => diffuse(self.color(&p, "reflectance")?.unwrap_or(Color::splat(0.5))),
            "conductor" | "roughconductor" => {
                if p.kind == "roughconductor" {
                    for name in ["alpha", "alpha_u", "alpha_v", "distribution", "sample_visible"] {
                        let _ = self.prop(&p, name);
                    }
                    self.warn(el, "roughconductor is rendered as a smooth mirror (its roughness is ignored)")?;
                }
                let material = self.string(&p, "material")?;
                let (eta, k) = (self.prop(&p, "eta"), self.prop(&p, "k"));
                if let Some((name, at)) = &material
                    && name != "none"
                {
                    self.warn(at, format!("conductor material `{name}` is rendered as a perfect (untinted) mirror"))?;
                } else if eta.is_some() || k.is_some() {
                    self.warn(el, "conductor eta/k are not supported: rendered as a perfect (untinted) mirror")?;
                }
                let kr = match self.color(&p, "specular_reflectance")? {
                    None => 1.0,
                    Some(c) => {
                        let mean = (c.x + c.y + c.z) / 3.0;
                        if c.max_element() - c.min_element() > 1e-6 {
                            self.warn(el, format!("tinted specular_reflectance {c} is taken as its mean {mean}"))?;
                        }
                        mean.clamp(0.0, 1.0)
                    }
                };
                mirror(kr)
            }
            "dielectric" | "roughdielectric" | "thindielectric" => {
                if p.kind == "roughdielectric" {
                    for name in ["alpha", "alpha_u", "alpha_v", "distribution", "sample_visible"] {
                        let _ = self.prop(&p, name);
                    }
                    self.warn(el, "roughdielectric is rendered as smooth glass (its roughness is ignored)")?;
                }
                let int_ior = self.ior(&p, "int_ior", 1.5046)?;
                let ext_ior = self.ior(&p, "ext_ior", 1.000277)?;
                for name in ["specular_reflectance", "specular_transmittance"] {
                    if let Some(c) = self.color(&p, name)?
                        && c != Color::ONE
                    {
                        self.warn(el, format!("`{name}` other than 1 is not supported and is ignored"))?;
                    }
                }
                let eta = int_ior / ext_ior;
                if p.kind == "thindielectric" {
                    // A thin sheet: light passes straight through, and the sheet reflects
                    // R + T^2 R / (1 - R^2) = 2R / (1 + R). We keep its value at normal incidence.
                    let r = f0(eta);
                    let kr = 2.0 * r / (1.0 + r);
                    self.warn(el, format!("thindielectric is approximated with a fixed reflectance {kr:.4} (its value at normal incidence)"))?;
                    Material {
                        kind: MaterialKind::Transparent,
                        color: Color::ONE,
                        ka: 0.0,
                        kd: 0.0,
                        ks: 0.0,
                        kr,
                        kt: 1.0 - kr,
                        ior: 1.0,
                        ..Material::default()
                    }
                } else {
                    Material {
                        kind: MaterialKind::Dielectric,
                        color: Color::ONE,
                        ka: 0.0,
                        kd: 0.0,
                        ks: 0.0,
                        ior: eta,
                        ..Material::default()
                    }
                }
            }
            "plastic" | "roughplastic" => {
                let color = self.color(&p, "diffuse_reflectance")?.unwrap_or(Color::splat(0.5));
                let int_ior = self.ior(&p, "int_ior", 1.49)?;
                let ext_ior = self.ior(&p, "ext_ior", 1.000277)?;
                for name in ["alpha", "distribution", "nonlinear", "sample_visible", "specular_reflectance"] {
                    let _ = self.prop(&p, name);
                }
                if p.kind == "plastic" {
                    let kr = f0(int_ior / ext_ior);
                    self.warn(el, format!("plastic is approximated by a diffuse base with albedo (1 - {kr:.3}) x reflectance and a mirror coat of constant reflectance {kr:.3}"))?;
                    Material {
                        kind: MaterialKind::Reflective,
                        color,
                        ka: 0.0,
                        kd: 1.0 - kr,
                        ks: 0.0,
                        kr,
                        ..Material::default()
                    }
                } else {
                    self.warn(el, "roughplastic is approximated by its diffuse base (the glossy coat is dropped)")?;
                    diffuse(color)
                }
            }
            "twosided" => {
                // Our surfaces reflect the same way on both sides already.
                let inner = self.object(&p, None, "bsdf");
                match inner.as_slice() {
                    [] => return Err(self.err(el, "twosided needs a nested <bsdf>")),
                    [(first, _), rest @ ..] => {
                        if !rest.is_empty() {
                            self.warn(
                                el,
                                "twosided with a different back side is not supported: both sides use the first BSDF",
                            )?;
                        }
                        self.bsdf(first, depth + 1)?
                    }
                }
            }
            other => {
                self.warn(el, format!("BSDF `{other}` is not supported: rendered as grey diffuse (reflectance 0.5)"))?;
                for u in &p.used {
                    u.set(true);
                }
                diffuse(Color::splat(0.5))
            }
        };
        self.finish(&p)?;
        Ok(m)
    }
}
