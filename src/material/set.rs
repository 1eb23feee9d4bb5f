//! A scene's materials and textures, and the one place a hit's material becomes its BSDF:
//! wrappers (two-sided, masks, bump and normal maps, blends) are resolved here, untextured
//! materials' lobes come from a table made once, textured ones are evaluated at the hit's (u, v).

use super::bsdf::{Bsdf, LobeSet, Lobes, MAX_LOBES, front_side};
use super::{Classic, GivenSpectra, GivenSpectrum, Material, Model, Plain, Wrapper};
use crate::geometry::Hit;
use crate::math::{Frame, Vec2, Vec3};
use crate::texture::{MeshPoint, TexPoint, Texture};

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
    /// Reflectance-like spectra given as spectra (`super::given`), which spectral mode evaluates
    /// instead of lifting the colours they stand for.
    pub spectra: Vec<GivenSpectrum>,
    /// Per material (or none past the end): the spectra of its constant colours in `spectra`.
    given: Vec<GivenSpectra>,
    /// Some material is a mask: shadow rays must look through transparent parts.
    pub has_masks: bool,
    /// Per material: it (or a material it wraps) reads a mesh attribute texture, so its BSDF
    /// needs the hit's triangle and barycentrics.
    reads_attributes: Vec<bool>,
}

impl Materials {
    /// Checks the references between materials and textures and prepares the tables. Errors
    /// name the material.
    pub fn new(list: Vec<Material>, names: Vec<String>, textures: Vec<Texture>) -> Result<Self, String> {
        Self::with_spectra(list, names, textures, Vec::new(), Vec::new())
    }

    /// `new`, with the spectra given for the materials' constant colours: `given[m]` for
    /// material `m`, indices into `spectra`.
    pub fn with_spectra(
        list: Vec<Material>,
        names: Vec<String>,
        textures: Vec<Texture>,
        spectra: Vec<GivenSpectrum>,
        given: Vec<GivenSpectra>,
    ) -> Result<Self, String> {
        let known = |id: super::SpectrumId| id.is_none() || (id.index() < spectra.len());
        if let Some(i) = given.iter().position(|g| !g.colors.iter().chain([&g.eta, &g.k]).all(|&id| known(id))) {
            let name = names.get(i).map_or("?", String::as_str);
            return Err(format!("material `{name}` refers to a spectrum that does not exist"));
        }
        for (i, m) in list.iter().enumerate() {
            let name = names.get(i).map_or("?", String::as_str);
            for c in m.model.children() {
                if c as usize >= i {
                    return Err(format!("material `{name}` refers to a material defined after it"));
                }
            }
            let texture_ok = |t: u32| (t as usize) < textures.len();
            if let Some(t) = m.model.params().iter().filter_map(|p| p.texture()).find(|&t| !texture_ok(t)) {
                return Err(format!("material `{name}` refers to texture {t}, which does not exist"));
            }
            if let Model::Wrapper(Wrapper::BumpMap { height, .. }) = m.model
                && !matches!(textures[height as usize], Texture::Bitmap(_))
            {
                return Err(format!("bump map `{name}` needs a bitmap texture for its heights"));
            }
            // Shadow rays and normal maps read textures by (u, v) alone.
            let attribute = |t: u32| matches!(textures[t as usize], Texture::MeshAttribute { .. });
            match m.model {
                Model::Wrapper(Wrapper::Mask { opacity: super::Param::Texture(t), .. }) if attribute(t) => {
                    return Err(format!("mask `{name}`: a mesh attribute cannot be its opacity"));
                }
                Model::Wrapper(Wrapper::NormalMap { normals, .. }) if attribute(normals) => {
                    return Err(format!("normal map `{name}` needs a bitmap texture, not a mesh attribute"));
                }
                _ => {}
            }
        }
        let mut set = Materials {
            list,
            names,
            textures,
            cached: Vec::new(),
            spectra,
            given,
            has_masks: false,
            reads_attributes: Vec::new(),
        };
        for i in 0..set.list.len() {
            if let Model::Wrapper(Wrapper::Blend { first, second, .. }) = set.list[i].model {
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
        set.has_masks = set.list.iter().any(|m| matches!(m.model, Model::Wrapper(Wrapper::Mask { .. })));
        set.cached = set
            .list
            .iter()
            .enumerate()
            .map(|(i, m)| match m.model {
                Model::Plain(p) if !p.is_textured() => {
                    let at = TexPoint::uv(Vec2::ZERO);
                    let given = set.given_of(i as u32);
                    Some([p.lobes(true, at, &set.textures, &given), p.lobes(false, at, &set.textures, &given)])
                }
                Model::Plain(_) | Model::Wrapper(_) => None,
            })
            .collect();
        // Materials refer only to earlier ones, so one pass in order sees every child first.
        for i in 0..set.list.len() {
            let model = &set.list[i].model;
            let own = model
                .params()
                .iter()
                .filter_map(|p| p.texture())
                .any(|t| matches!(set.textures[t as usize], Texture::MeshAttribute { .. }));
            let reads = own || model.children().any(|c| set.reads_attributes[c as usize]);
            set.reads_attributes.push(reads);
        }
        Ok(set)
    }

    /// True when material `m`'s BSDF reads mesh attributes (`bsdf` then needs its `mesh`).
    #[inline]
    pub fn reads_mesh_attributes(&self, m: u32) -> bool {
        self.reads_attributes.get(m as usize).copied().unwrap_or(false)
    }

    fn depth(&self, m: u32) -> usize {
        1 + self.list[m as usize].model.children().map(|c| self.depth(c)).max().unwrap_or(0)
    }

    /// The one walk through wrappers: from material `m`, seen from the outward side (`front`)
    /// or not, through each wrapper (`visit` sees it: a mask's opacity, a bump map's frame) to
    /// where the wrappers end, and whether a two-sided wrapper chose the side on the way.
    #[inline]
    fn walk(&self, m: u32, front: bool, mut visit: impl FnMut(&Wrapper)) -> (WalkEnd, bool) {
        let mut m = m;
        let mut as_front = false;
        for _ in 0..=MAX_NESTING {
            match &self.list[m as usize].model {
                Model::Plain(_) => return (WalkEnd::Plain(m), as_front),
                Model::Wrapper(w) => {
                    visit(w);
                    as_front |= matches!(w, Wrapper::TwoSided { .. });
                    match w.next(front) {
                        Some(next) => m = next,
                        None => return (WalkEnd::Blend(m), as_front),
                    }
                }
            }
        }
        // Deeper nesting is refused when the set is made.
        (WalkEnd::Black, as_front)
    }

    /// Lobes a plain material (or the plain material a chain of wrappers ends in) has.
    fn plain_lobes_of(&self, m: u32) -> Lobes {
        match self.walk(m, true, |_| {}).0 {
            WalkEnd::Plain(p) => {
                self.plain(p).lobes(true, TexPoint::uv(Vec2::ZERO), &self.textures, &GivenSpectra::NONE)
            }
            WalkEnd::Blend(_) | WalkEnd::Black => Lobes::default(),
        }
    }

    fn plain_lobe_count(&self, m: u32) -> usize {
        match self.list[m as usize].model {
            Model::Wrapper(Wrapper::Blend { first, second, .. }) => {
                self.plain_lobe_count(first) + self.plain_lobe_count(second)
            }
            Model::Plain(_) | Model::Wrapper(_) => self.plain_lobes_of(m).len().max(1),
        }
    }

    /// The plain model of material `m`, which a walk ended at (a wrapper there is a bug: black).
    #[inline]
    fn plain(&self, m: u32) -> &Plain {
        static BLACK: Plain = Plain::Classic(Classic::BLACK);
        match &self.list[m as usize].model {
            Model::Plain(p) => p,
            Model::Wrapper(_) => &BLACK,
        }
    }

    /// The spectra given for material `m`'s constant colours.
    #[inline]
    fn given_of(&self, m: u32) -> GivenSpectra {
        self.given.get(m as usize).copied().unwrap_or(GivenSpectra::NONE)
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
    fn lobes(&self, m: u32, at: TexPoint<'_>, front: bool, as_front: bool) -> LobeSet<'_> {
        let Some(outward) = self.outward(m, front, as_front) else { return LobeSet::Owned(Lobes::default()) };
        if let Some(c) = &self.cached[m as usize] {
            return LobeSet::Shared(&c[usize::from(!outward)]);
        }
        LobeSet::Owned(self.plain(m).lobes(outward, at, &self.textures, &self.given_of(m)))
    }

    /// Which lobes plain material `m` shows on side `front` (`as_front` as in `lobes`): its
    /// outward ones (`true`), its inward ones (glass seen from inside, whose index is
    /// inverted), or none (`None`: the back of a one-sided material).
    #[inline]
    fn outward(&self, m: u32, front: bool, as_front: bool) -> Option<bool> {
        let material = &self.list[m as usize];
        let glass = self.plain(m).is_glass();
        (front || as_front || material.two_sided || glass).then_some(front || !glass)
    }

    /// The BSDF at hit `h` seen from direction `wo` (towards the viewer); `mesh` is where the
    /// hit is on a mesh, for materials that read mesh attributes (`reads_mesh_attributes`).
    #[inline]
    pub fn bsdf(&self, h: &Hit, wo: Vec3, mesh: Option<MeshPoint<'_>>) -> Bsdf<'_> {
        let front = front_side(wo, h.ng);
        let m = h.material;
        // The common case: a plain untextured material, whose lobes were made once. The BSDF
        // is built around a reference to them here, field by field (moving a `LobeSet` through
        // a function result copies the whole of its largest variant, a few hundred bytes).
        if let Some(c) = &self.cached[m as usize] {
            let Some(outward) = self.outward(m, front, false) else {
                return Bsdf::new(frame_for(h, &Lobes::default()), h.ng, front, Lobes::default());
            };
            let lobes = &c[usize::from(!outward)];
            return Bsdf::shared(frame_for(h, lobes), h.ng, front, lobes);
        }
        // Then a plain textured one.
        if let Model::Plain(_) = self.list[m as usize].model {
            let lobes = self.lobes(m, TexPoint { uv: h.uv(), mesh }, front, false);
            return Bsdf::with_lobes(frame_for(h, &lobes), h.ng, front, lobes);
        }
        self.wrapped_bsdf(h, wo, front, TexPoint { uv: h.uv(), mesh })
    }

    /// `bsdf` through wrappers.
    fn wrapped_bsdf(&self, h: &Hit, wo: Vec3, front: bool, at: TexPoint<'_>) -> Bsdf<'_> {
        let uv = at.uv;
        let mut opacity = 1.0f32;
        // The perturbed shading frame, outward, when a bump or normal map applies.
        let mut perturbed: Option<Frame> = None;
        let (end, as_front) = self.walk(h.material, front, |w| match *w {
            Wrapper::Mask { opacity: o, .. } => opacity *= o.at(at, &self.textures).clamp(0.0, 1.0),
            Wrapper::BumpMap { height, scale, .. } => {
                let base = perturbed.unwrap_or_else(|| h.shading_frame());
                perturbed = Some(self.bump_frame(h, &base, height, scale, wo));
            }
            Wrapper::NormalMap { normals, .. } => {
                let base = perturbed.unwrap_or_else(|| h.shading_frame());
                let rgb = self.textures[normals as usize].eval(uv);
                perturbed = Some(perturbed_frame(&base, rgb.to_vec3() * 2.0 - Vec3::ONE, wo));
            }
            Wrapper::TwoSided { .. } | Wrapper::Blend { .. } => {}
        });
        let mut lobes = Lobes::default();
        match end {
            WalkEnd::Plain(m) => lobes = *self.lobes(m, at, front, as_front),
            WalkEnd::Blend(m) => self.add_blend_lobes(m, at, front, as_front, 1.0, &mut lobes, 0),
            WalkEnd::Black => {}
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
        at: TexPoint<'_>,
        front: bool,
        as_front: bool,
        scale: f32,
        out: &mut Lobes,
        depth: usize,
    ) {
        if depth > MAX_NESTING || !(scale > 0.0) {
            return;
        }
        if let Model::Wrapper(Wrapper::Blend { weight, first, second }) = self.list[m as usize].model {
            let w = weight.at(at, &self.textures).clamp(0.0, 1.0);
            self.add_blend_lobes(first, at, front, as_front, scale * (1.0 - w), out, depth + 1);
            self.add_blend_lobes(second, at, front, as_front, scale * w, out, depth + 1);
            return;
        }
        // A blend's part resolves to its plain material: its wrappers are not applied inside a
        // blend (the loaders warn or refuse), a two-sided one giving its front.
        match self.walk(m, true, |_| {}).0 {
            // A blend behind wrappers: its wrappers are dropped, its parts still count.
            WalkEnd::Blend(end) => self.add_blend_lobes(end, at, front, as_front, scale, out, depth + 1),
            WalkEnd::Plain(end) => out.add_scaled(&self.lobes(end, at, front, as_front), scale),
            WalkEnd::Black => {}
        }
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

    /// The spectral-mode index ratio of the material at hit `h`, seen from side `front`, for the
    /// hero wavelength `lambda` (nm): n(lambda) / n_d for a dispersive glass seen from outside,
    /// its inverse from inside (its lobes' relative index is inverted there); `None` when the
    /// material is not dispersive. Only a plain glass material disperses: a dispersive glass
    /// wrapped by another material is rendered with its d-line index.
    #[inline]
    pub fn dispersion(&self, h: &Hit, front: bool, lambda: f32) -> Option<f32> {
        let d = self.list.get(h.material as usize)?.dispersion?;
        let r = d.eval(lambda) / d.n_d();
        Some(if front { r } else { 1.0 / r })
    }

    /// How much of the light a shadow ray carries past hit `h`: 1 - opacity for a mask's
    /// transparent part, 0 for everything else.
    #[inline]
    pub fn transparency(&self, h: &Hit, toward_front: bool) -> f32 {
        let mut opacity = 1.0f32;
        self.walk(h.material, toward_front, |w| match *w {
            Wrapper::Mask { opacity: o, .. } => opacity *= o.at(TexPoint::uv(h.uv()), &self.textures).clamp(0.0, 1.0),
            Wrapper::TwoSided { .. } | Wrapper::BumpMap { .. } | Wrapper::NormalMap { .. } | Wrapper::Blend { .. } => {}
        });
        1.0 - opacity
    }

    /// True when light through material `m` can focus into caustics (see
    /// `Plain::casts_caustics`).
    pub fn casts_caustics(&self, m: u32) -> bool {
        let model = &self.list[m as usize].model;
        let own = match model {
            Model::Plain(p) => p.casts_caustics(),
            Model::Wrapper(_) => false,
        };
        own || model.children().any(|c| self.casts_caustics(c))
    }
}

/// The shading frame for `lobes`: isotropic lobes need only the normal (a frame from it alone
/// saves the Gram-Schmidt step and a sphere's dp/du); anisotropic ones follow dp/du. The usual
/// case is made in the caller: a frame returned from a call is written to memory in pieces and
/// read back whole, and the read waits for the writes.
#[inline(always)]
fn frame_for(h: &Hit, lobes: &Lobes) -> Frame {
    if lobes.is_isotropic() { Frame::from_z(h.ns) } else { anisotropic_frame(h) }
}

#[inline(never)]
fn anisotropic_frame(h: &Hit) -> Frame {
    h.shading_frame()
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

/// Where a walk through wrappers ends (`Materials::walk`).
#[derive(Clone, Copy, Debug)]
enum WalkEnd {
    /// At this plain material.
    Plain(u32),
    /// At this blend, whose two parts are walked each on its own.
    Blend(u32),
    /// Nowhere: wrappers nested deeper than a set allows (refused when it is made).
    Black,
}
