//! A scene's materials and textures, and the one place a hit's material becomes its BSDF:
//! wrappers (two-sided, masks, bump and normal maps, blends) are resolved here, untextured
//! materials' lobes come from a table made once, textured ones are evaluated at the hit's (u, v).

use super::bsdf::{Bsdf, LobeSet, Lobes, MAX_LOBES, front_side};
use super::fresnel::{fresnel_conductor_rgb, fresnel_dielectric};
use super::{Classic, ClassicKind, Material, Model, Param};
use crate::geometry::Hit;
use crate::math::{Color, Frame, Vec2, Vec3};
use crate::texture::Texture;

/// Wrappers nest at most this deep (a mask of a bump map of a two-sided material is 3).
pub const MAX_NESTING: usize = 8;

/// The materials of a scene with the textures they read.
#[derive(Clone, Debug, Default)]
pub struct Materials {
    pub list: Vec<Material>,
    pub names: Vec<String>,
    pub textures: Vec<Texture>,
    /// Lobes of untextured plain materials seen from the front and from the back, made once.
    cached: Vec<Option<[Lobes; 2]>>,
    /// What the Whitted integrator shades each material with.
    classic: Vec<Classic>,
    /// Some material is a mask: shadow rays must look through transparent parts.
    pub has_masks: bool,
}

impl Materials {
    /// Checks the references between materials and textures and prepares the tables. Errors
    /// name the material.
    pub fn new(list: Vec<Material>, names: Vec<String>, textures: Vec<Texture>) -> Result<Self, String> {
        for (i, m) in list.iter().enumerate() {
            let name = names.get(i).map_or("?", String::as_str);
            for c in m.model.children() {
                if c as usize >= i {
                    return Err(format!("material `{name}` refers to a material defined after it"));
                }
            }
            let texture_ok = |t: u32| (t as usize) < textures.len();
            let textures_used = texture_refs(&m.model);
            if let Some(t) = textures_used.into_iter().find(|&t| !texture_ok(t)) {
                return Err(format!("material `{name}` refers to texture {t}, which does not exist"));
            }
            if let Model::BumpMap { height, .. } = m.model
                && !matches!(textures[height as usize], Texture::Bitmap(_))
            {
                return Err(format!("bump map `{name}` needs a bitmap texture for its heights"));
            }
        }
        let mut set = Materials { list, names, textures, cached: Vec::new(), classic: Vec::new(), has_masks: false };
        for i in 0..set.list.len() {
            if let Model::Blend { first, second, .. } = set.list[i].model {
                let n = set.plain_lobe_count(first) + set.plain_lobe_count(second);
                if n > MAX_LOBES {
                    let name = set.names.get(i).map_or("?", String::as_str);
                    return Err(format!(
                        "blend `{name}` mixes materials with {n} lobes in all; at most {MAX_LOBES} can be blended"
                    ));
                }
            }
            if set.depth(i as u32) > MAX_NESTING {
                let name = set.names.get(i).map_or("?", String::as_str);
                return Err(format!("material `{name}` nests wrappers more than {MAX_NESTING} deep"));
            }
        }
        set.has_masks = set.list.iter().any(|m| matches!(m.model, Model::Mask { .. }));
        set.cached = set
            .list
            .iter()
            .map(|m| {
                let plain = !m.model.is_textured();
                plain.then(|| {
                    [m.model.lobes(true, Vec2::ZERO, &set.textures), m.model.lobes(false, Vec2::ZERO, &set.textures)]
                })
            })
            .collect();
        set.classic = (0..set.list.len()).map(|i| set.classic_view(i as u32)).collect();
        Ok(set)
    }

    fn depth(&self, m: u32) -> usize {
        1 + self.list[m as usize].model.children().into_iter().map(|c| self.depth(c)).max().unwrap_or(0)
    }

    /// Lobes a plain material (or the plain material a chain of wrappers ends in) has.
    fn plain_lobes_of(&self, m: u32) -> Lobes {
        let mut m = m;
        for _ in 0..MAX_NESTING {
            match self.list[m as usize].model {
                Model::TwoSided { front, .. } => m = front,
                Model::BumpMap { inner, .. } | Model::NormalMap { inner, .. } | Model::Mask { inner, .. } => m = inner,
                Model::Blend { .. } => return Lobes::default(),
                model => return model.lobes(true, Vec2::ZERO, &self.textures),
            }
        }
        Lobes::default()
    }

    fn plain_lobe_count(&self, m: u32) -> usize {
        match self.list[m as usize].model {
            Model::Blend { first, second, .. } => self.plain_lobe_count(first) + self.plain_lobe_count(second),
            _ => self.plain_lobes_of(m).len().max(1),
        }
    }

    pub fn len(&self) -> usize {
        self.list.len()
    }

    pub fn is_empty(&self) -> bool {
        self.list.is_empty()
    }

    /// The lobes of plain material `m` at `uv` on side `front` (`as_front`: a two-sided wrapper
    /// decided the side already).
    #[inline]
    fn lobes(&self, m: u32, uv: Vec2, front: bool, as_front: bool) -> LobeSet<'_> {
        let Some(outward) = self.outward(m, front, as_front) else { return LobeSet::Owned(Lobes::default()) };
        if let Some(c) = &self.cached[m as usize] {
            return LobeSet::Shared(&c[usize::from(!outward)]);
        }
        LobeSet::Owned(self.list[m as usize].model.lobes(outward, uv, &self.textures))
    }

    /// Which lobes plain material `m` shows on side `front` (`as_front` as in `lobes`): its
    /// outward ones (`true`), its inward ones (glass seen from inside, whose index is
    /// inverted), or none (`None`: the back of a one-sided material).
    #[inline]
    fn outward(&self, m: u32, front: bool, as_front: bool) -> Option<bool> {
        let material = &self.list[m as usize];
        let glass = material.model.is_glass();
        (front || as_front || material.two_sided || glass).then_some(front || !glass)
    }

    /// The BSDF at hit `h` seen from direction `wo` (towards the viewer).
    #[inline]
    pub fn bsdf(&self, h: &Hit, wo: Vec3) -> Bsdf<'_> {
        let front = front_side(wo, h.ng);
        let m = h.material;
        // The common case: a plain untextured material, whose lobes were made once. The BSDF
        // is built around a reference to them here, field by field (moving a `LobeSet` through
        // a function result copies all 248 bytes of its largest variant).
        if let Some(c) = &self.cached[m as usize] {
            let Some(outward) = self.outward(m, front, false) else {
                return Bsdf::new(frame_for(h, &Lobes::default()), h.ng, front, Lobes::default());
            };
            let lobes = &c[usize::from(!outward)];
            return Bsdf::shared(frame_for(h, lobes), h.ng, front, lobes);
        }
        // Then a plain textured one.
        if !matches!(
            self.list[m as usize].model,
            Model::TwoSided { .. }
                | Model::BumpMap { .. }
                | Model::NormalMap { .. }
                | Model::Mask { .. }
                | Model::Blend { .. }
        ) {
            let lobes = self.lobes(m, h.uv(), front, false);
            return Bsdf::with_lobes(frame_for(h, &lobes), h.ng, front, lobes);
        }
        self.wrapped_bsdf(h, wo, front)
    }

    /// `bsdf` through wrappers.
    fn wrapped_bsdf(&self, h: &Hit, wo: Vec3, front: bool) -> Bsdf<'_> {
        let uv = h.uv();
        let mut m = h.material;
        let mut opacity = 1.0f32;
        let mut as_front = false;
        // The perturbed shading frame, outward, when a bump or normal map applies.
        let mut perturbed: Option<Frame> = None;
        let mut lobes = Lobes::default();
        for _ in 0..=MAX_NESTING {
            match self.list[m as usize].model {
                Model::TwoSided { front: a, back: b } => {
                    m = if front { a } else { b };
                    as_front = true;
                }
                Model::Mask { opacity: o, inner } => {
                    opacity *= o.at(uv, &self.textures).clamp(0.0, 1.0);
                    m = inner;
                }
                Model::BumpMap { height, scale, inner } => {
                    let base = perturbed.unwrap_or_else(|| h.shading_frame());
                    perturbed = Some(self.bump_frame(h, &base, height, scale, wo));
                    m = inner;
                }
                Model::NormalMap { normals, inner } => {
                    let base = perturbed.unwrap_or_else(|| h.shading_frame());
                    let rgb = self.textures[normals as usize].eval(uv);
                    perturbed = Some(perturbed_frame(&base, rgb.to_vec3() * 2.0 - Vec3::ONE, wo));
                    m = inner;
                }
                Model::Blend { .. } => {
                    self.add_blend_lobes(m, uv, front, as_front, 1.0, &mut lobes, 0);
                    break;
                }
                _ => {
                    lobes = *self.lobes(m, uv, front, as_front);
                    break;
                }
            }
        }
        let frame = match perturbed {
            Some(_) => h.shading_frame(),
            None => frame_for(h, &lobes),
        };
        let mut bsdf = Bsdf::new(frame, h.ng, front, lobes).with_opacity(opacity);
        if let Some(p) = perturbed {
            bsdf = bsdf.perturbed(if front { p } else { p.flipped() });
        }
        bsdf
    }

    /// Adds the lobes of blend `m` (blends nested in it included), each part's lobes scaled by
    /// `scale` times its weight.
    #[allow(clippy::too_many_arguments)]
    fn add_blend_lobes(
        &self,
        m: u32,
        uv: Vec2,
        front: bool,
        as_front: bool,
        scale: f32,
        out: &mut Lobes,
        depth: usize,
    ) {
        if depth > MAX_NESTING || !(scale > 0.0) {
            return;
        }
        if let Model::Blend { weight, first, second } = self.list[m as usize].model {
            let w = weight.at(uv, &self.textures).clamp(0.0, 1.0);
            self.add_blend_lobes(first, uv, front, as_front, scale * (1.0 - w), out, depth + 1);
            self.add_blend_lobes(second, uv, front, as_front, scale * w, out, depth + 1);
            return;
        }
        let end = self.plain_end(m);
        if matches!(self.list[end as usize].model, Model::Blend { .. }) {
            // A blend behind wrappers: its wrappers are dropped, its parts still count.
            self.add_blend_lobes(end, uv, front, as_front, scale, out, depth + 1);
        } else {
            out.add_scaled(&self.lobes(end, uv, front, as_front), scale);
        }
    }

    /// The plain material a blend's part resolves to (its wrappers are not applied inside a
    /// blend: the loader warns).
    fn plain_end(&self, m: u32) -> u32 {
        let mut m = m;
        for _ in 0..MAX_NESTING {
            match self.list[m as usize].model {
                Model::TwoSided { front, .. } => m = front,
                Model::BumpMap { inner, .. } | Model::NormalMap { inner, .. } | Model::Mask { inner, .. } => m = inner,
                _ => return m,
            }
        }
        m
    }

    /// The shading frame tilted by a height texture: dp/du and dp/dv move along the normal by
    /// the height's gradient times `scale`, and the new normal is their cross product.
    fn bump_frame(&self, h: &Hit, base: &Frame, height: u32, scale: f32, wo: Vec3) -> Frame {
        let Texture::Bitmap(b) = &self.textures[height as usize] else { return *base };
        let (_, g) = b.eval_1_grad(h.uv());
        let n = base.z;
        let (dpdu, dpdv) = (h.dpdu(), h.dpdv());
        let du = dpdu + n * (scale * g.x - n.dot(dpdu));
        let dv = dpdv + n * (scale * g.y - n.dot(dpdv));
        let mut n2 = du.cross(dv).normalize_or_zero();
        if n2 == Vec3::ZERO || !n2.is_finite() {
            return *base;
        }
        if n2.dot(h.ng) < 0.0 {
            n2 = -n2;
        }
        perturbed_frame(base, base.to_local(n2), wo)
    }

    /// How much of the light a shadow ray carries past hit `h`: 1 - opacity for a mask's
    /// transparent part, 0 for everything else.
    #[inline]
    pub fn transparency(&self, h: &Hit, toward_front: bool) -> f32 {
        let mut m = h.material;
        let mut opacity = 1.0f32;
        for _ in 0..=MAX_NESTING {
            match self.list[m as usize].model {
                Model::TwoSided { front, back } => m = if toward_front { front } else { back },
                Model::Mask { opacity: o, inner } => {
                    opacity *= o.at(h.uv(), &self.textures).clamp(0.0, 1.0);
                    m = inner;
                }
                Model::BumpMap { inner, .. } | Model::NormalMap { inner, .. } => m = inner,
                _ => break,
            }
        }
        1.0 - opacity
    }

    /// What the Whitted integrator shades hit `h` with (the classic model, textures applied).
    #[inline(always)]
    pub fn classic(&self, h: &Hit) -> Classic {
        let c = self.classic[h.material as usize];
        match c.color_texture {
            Some(t) => Classic { color: self.textures[t as usize].eval(h.uv()), ..c },
            None => c,
        }
    }

    /// The classic material of index `m` (without its texture).
    pub fn classic_of(&self, m: u32) -> &Classic {
        &self.classic[m as usize]
    }

    /// True when light through material `m` can focus into caustics (see
    /// `Model::casts_caustics`).
    pub fn casts_caustics(&self, m: u32) -> bool {
        let model = &self.list[m as usize].model;
        model.casts_caustics() || model.children().into_iter().any(|c| self.casts_caustics(c))
    }

    /// True when some part of material `m` transmits light.
    pub fn is_glass(&self, m: u32) -> bool {
        let model = &self.list[m as usize].model;
        model.is_glass() || model.children().into_iter().any(|c| self.is_glass(c))
    }

    /// The Whitted view of material `m`: the classic model as it is, and for the others the
    /// nearest classic reading (documented in docs/scene-format.md): diffuse colours, mirrors
    /// with the normal-incidence reflectance of metals and coatings, Phong highlights of the
    /// matching width for rough surfaces, glass as glass. Roughness of glass, textures other than
    /// a diffuse colour, masks and bump maps are ignored.
    fn classic_view(&self, m: u32) -> Classic {
        let const_or_mean = |p: &Param<Color>| match *p {
            Param::Const(c) => (c, None),
            Param::Texture(t) => (self.textures[t as usize].mean(), Some(t)),
        };
        let exponent = |alpha: f32| (2.0 / (alpha * alpha).max(1e-4) - 2.0).clamp(1.0, 10_000.0);
        let alpha_of = |p: &Param<f32>| match *p {
            Param::Const(a) => a,
            Param::Texture(t) => {
                let c = self.textures[t as usize].mean();
                c.mean()
            }
        };
        let base = Classic { ka: 0.0, ks: 0.0, kr: 0.0, kt: 0.0, ..Classic::default() };
        match self.list[m as usize].model {
            Model::Classic(c) => c,
            Model::Diffuse { reflectance } => {
                let (color, color_texture) = const_or_mean(&reflectance);
                Classic { kind: ClassicKind::Diffuse, color, color_texture, kd: 1.0, ..base }
            }
            Model::Conductor { eta, k, specular } => {
                let f0 = fresnel_conductor_rgb(1.0, eta, k) * const_or_mean(&specular).0;
                Classic { kind: ClassicKind::Reflective, color: f0, kd: 0.0, kr: f0.mean(), ..base }
            }
            Model::RoughConductor { roughness, eta, k, specular } => {
                let f0 = fresnel_conductor_rgb(1.0, eta, k) * const_or_mean(&specular).0;
                let n = exponent(alpha_of(&roughness.alpha_u).max(alpha_of(&roughness.alpha_v)));
                Classic { kind: ClassicKind::Diffuse, color: f0, kd: 0.0, ks: f0.mean(), exponent: n, ..base }
            }
            Model::Dielectric { eta, .. } | Model::RoughDielectric { eta, .. } => {
                Classic { kind: ClassicKind::Dielectric, ior: eta, kd: 0.0, ..base }
            }
            Model::Plastic { diffuse, eta, .. } => {
                let (color, color_texture) = const_or_mean(&diffuse);
                let f0 = fresnel_dielectric(1.0, eta);
                Classic { kind: ClassicKind::Reflective, color, color_texture, kd: 1.0 - f0, kr: f0, ..base }
            }
            Model::RoughPlastic { microfacet, diffuse, eta, .. } => {
                let (color, color_texture) = const_or_mean(&diffuse);
                let f0 = fresnel_dielectric(1.0, eta);
                let n = exponent(microfacet.alpha_u);
                Classic { kind: ClassicKind::Diffuse, color, color_texture, kd: 1.0 - f0, ks: f0, exponent: n, ..base }
            }
            Model::TwoSided { front: inner, .. }
            | Model::BumpMap { inner, .. }
            | Model::NormalMap { inner, .. }
            | Model::Mask { inner, .. } => self.classic_view(inner),
            Model::Blend { weight, first, second } => {
                let w = alpha_of(&weight).clamp(0.0, 1.0);
                if w < 0.5 { self.classic_view(first) } else { self.classic_view(second) }
            }
        }
    }
}

/// The shading frame for `lobes`: isotropic lobes need only the normal (a frame from it alone
/// saves the Gram-Schmidt step and a sphere's dp/du); anisotropic ones follow dp/du.
#[inline]
fn frame_for(h: &Hit, lobes: &Lobes) -> Frame {
    if lobes.is_isotropic() { Frame::from_z(h.ns) } else { h.shading_frame() }
}

/// The frame of `base` tilted to the local normal `n_local`, as Mitsuba 3 builds it: a normal
/// that would put the viewer on its other side is mirrored about the old normal; the new tangent
/// is the old one made perpendicular.
fn perturbed_frame(base: &Frame, n_local: Vec3, wo: Vec3) -> Frame {
    let mut n = n_local.normalize_or_zero();
    if n == Vec3::ZERO || !n.is_finite() {
        return *base;
    }
    let wo_l = base.to_local(wo);
    if wo_l.z * wo_l.dot(n) <= 0.0 {
        n = Vec3::new(-n.x, -n.y, n.z);
    }
    let s = (Vec3::X - n * n.x).normalize_or_zero();
    let s = if s == Vec3::ZERO { Frame::from_z(n).x } else { s };
    let t = n.cross(s);
    Frame { x: base.to_world(s), y: base.to_world(t), z: base.to_world(n) }
}

/// Every texture index a model reads.
fn texture_refs(model: &Model) -> Vec<u32> {
    let mut out = Vec::new();
    let mut c = |p: &Param<Color>| {
        if let Param::Texture(t) = p {
            out.push(*t)
        }
    };
    match model {
        Model::Classic(cl) => {
            if let Some(t) = cl.color_texture {
                c(&Param::Texture(t));
            }
        }
        Model::Diffuse { reflectance } => c(reflectance),
        Model::Conductor { specular, .. } => c(specular),
        Model::RoughConductor { specular, .. } => c(specular),
        Model::Dielectric { reflectance, transmittance, .. }
        | Model::RoughDielectric { reflectance, transmittance, .. } => {
            c(reflectance);
            c(transmittance);
        }
        Model::Plastic { diffuse, specular, .. } | Model::RoughPlastic { diffuse, specular, .. } => {
            c(diffuse);
            c(specular);
        }
        Model::BumpMap { height, .. } => out.push(*height),
        Model::NormalMap { normals, .. } => out.push(*normals),
        _ => {}
    }
    let mut f = |p: &Param<f32>| {
        if let Param::Texture(t) = p {
            out.push(*t)
        }
    };
    match model {
        Model::RoughConductor { roughness, .. } | Model::RoughDielectric { roughness, .. } => {
            f(&roughness.alpha_u);
            f(&roughness.alpha_v);
        }
        Model::Mask { opacity, .. } => f(opacity),
        Model::Blend { weight, .. } => f(weight),
        _ => {}
    }
    out
}
