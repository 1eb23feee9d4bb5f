//! The primitives a BVH is built over, kept small: shapes are held whole (spheres, quads,
//! emitters, loose triangles: a scene has few), and each triangle of a mesh as two indices (8
//! bytes), its vertices read from the mesh when they are needed. A triangle held whole would
//! take 60 bytes and repeat the vertices the mesh and the BVH's leaves already hold.

use super::{CompactShape, PrimHit, Primitive, Shape, SurfacePoint, Triangle, TriangleMesh};
use crate::geometry::{Aabb, NO_LIGHT, Ray};

/// `PrimRef::group` of a shape held whole (then `index` is into `Primitives::shapes`).
const WHOLE: u32 = u32::MAX;

/// One primitive: a shape held whole, or triangle `index` of mesh group `group`.
#[derive(Clone, Copy, Debug)]
struct PrimRef {
    group: u32,
    index: u32,
}

/// A mesh whose triangles are primitives, and the material they share (mesh triangles never
/// emit: emitting meshes are added as a light per triangle, held whole).
#[derive(Clone, Copy, Debug)]
struct MeshGroup {
    mesh: u32,
    material: u32,
}

/// Primitives in order (the order given, until a BVH reorders them into its leaf order).
#[derive(Clone, Debug, Default)]
pub struct Primitives {
    refs: Vec<PrimRef>,
    shapes: Vec<Primitive>,
    groups: Vec<MeshGroup>,
}

impl Primitives {
    pub fn new() -> Self {
        Self::default()
    }

    pub fn len(&self) -> usize {
        self.refs.len()
    }

    pub fn is_empty(&self) -> bool {
        self.refs.is_empty()
    }

    /// Adds a shape held whole.
    pub fn push(&mut self, p: Primitive) {
        self.refs.push(PrimRef { group: WHOLE, index: self.shapes.len() as u32 });
        self.shapes.push(p);
    }

    /// Adds triangles `triangles` of mesh `mesh` (an index into the scene's meshes, which every
    /// later call is given as `meshes`), all with `material`; room is reserved for as many as
    /// the iterator may give.
    pub fn push_mesh(&mut self, mesh: u32, material: u32, triangles: impl Iterator<Item = u32>) {
        let group = self.groups.len() as u32;
        self.groups.push(MeshGroup { mesh, material });
        let (low, high) = triangles.size_hint();
        self.refs.reserve_exact(high.unwrap_or(low));
        self.refs.extend(triangles.map(|index| PrimRef { group, index }));
    }

    /// Adds all of `other` after these.
    pub fn append(&mut self, other: Primitives) {
        let (shapes, groups) = (self.shapes.len() as u32, self.groups.len() as u32);
        self.refs.extend(other.refs.into_iter().map(|r| match r.group {
            WHOLE => PrimRef { group: WHOLE, index: r.index + shapes },
            g => PrimRef { group: g + groups, index: r.index },
        }));
        self.shapes.extend(other.shapes);
        self.groups.extend(other.groups);
    }

    /// Primitive `i` with its shape (a mesh triangle with its vertices read from the mesh).
    #[inline]
    pub fn get(&self, i: usize, meshes: &[TriangleMesh]) -> Primitive {
        let r = self.refs[i];
        match r.group {
            WHOLE => self.shapes[r.index as usize],
            g => {
                let g = self.groups[g as usize];
                let mesh = &meshes[g.mesh as usize];
                let p = mesh.indices[r.index as usize].map(|v| mesh.positions[v as usize]);
                let shape = Shape::Triangle(Triangle { p, mesh: g.mesh, index: r.index });
                Primitive { shape, material: g.material, light: NO_LIGHT }
            }
        }
    }

    /// Material and light of primitive `i`.
    #[inline]
    pub fn material_light(&self, i: usize) -> (u32, u32) {
        let r = self.refs[i];
        match r.group {
            WHOLE => {
                let p = &self.shapes[r.index as usize];
                (p.material, p.light)
            }
            g => (self.groups[g as usize].material, NO_LIGHT),
        }
    }

    pub fn bounds(&self, i: usize, meshes: &[TriangleMesh]) -> Aabb {
        self.get(i, meshes).shape.bounds()
    }

    /// What intersection needs of primitive `i` (see `CompactShape`).
    pub fn compact(&self, i: usize, meshes: &[TriangleMesh]) -> CompactShape {
        self.get(i, meshes).shape.compact()
    }

    /// Surface data of primitive `i` at a hit `intersect` found on `leaf`, its compact shape: a
    /// mesh triangle takes its vertices from the leaf, which the test just read, rather than
    /// through the mesh's indices. (Material and light come from `material_light`: returned
    /// together with the surface, the whole went through a temporary whose copy stalled on the
    /// stores just made to it.)
    #[inline(always)]
    pub fn surface(
        &self,
        i: usize,
        leaf: &CompactShape,
        ray: &Ray,
        h: &PrimHit,
        meshes: &[TriangleMesh],
    ) -> SurfacePoint {
        let r = self.refs[i];
        match (r.group, leaf) {
            (WHOLE, _) => self.shapes[r.index as usize].shape.surface(ray, h, meshes),
            (g, CompactShape::Triangle(p)) => {
                let g = self.groups[g as usize];
                Triangle { p: *p, mesh: g.mesh, index: r.index }.surface(h, meshes)
            }
            // (A mesh triangle's leaf is always a triangle; kept total rather than panicking.)
            (
                _,
                CompactShape::Sphere(_)
                | CompactShape::Quad(_)
                | CompactShape::Disk(_)
                | CompactShape::Cylinder { .. }
                | CompactShape::Plane(_)
                | CompactShape::SdfVoxel(_),
            ) => self.get(i, meshes).shape.surface(ray, h, meshes),
        }
    }

    /// Reorders the primitives so that primitive `i` becomes the old `order[i]` (a gather on
    /// all threads: following the permutation's cycles in place took 15% of a big mesh's load).
    pub(crate) fn reorder(&mut self, order: &[u32]) {
        use rayon::prelude::*;
        self.refs = order.par_iter().map(|&i| self.refs[i as usize]).collect();
    }

    pub fn shrink_to_fit(&mut self) {
        self.refs.shrink_to_fit();
        self.shapes.shrink_to_fit();
        self.groups.shrink_to_fit();
    }

    /// Bytes held (the meshes' own arrays not included).
    pub fn memory_bytes(&self) -> usize {
        self.refs.capacity() * std::mem::size_of::<PrimRef>()
            + self.shapes.capacity() * std::mem::size_of::<Primitive>()
            + self.groups.capacity() * std::mem::size_of::<MeshGroup>()
    }
}

impl From<Vec<Primitive>> for Primitives {
    fn from(shapes: Vec<Primitive>) -> Self {
        let refs = (0..shapes.len() as u32).map(|index| PrimRef { group: WHOLE, index }).collect();
        Primitives { refs, shapes, groups: Vec::new() }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Vec3;
    use crate::shape::Sphere;

    fn mesh() -> TriangleMesh {
        TriangleMesh {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::new(1.0, 1.0, 0.0)],
            indices: vec![[0, 1, 2], [1, 3, 2]],
            ..Default::default()
        }
    }

    /// A mesh triangle held as indices gives the shape, material and bounds of the same
    /// triangle held whole, and `append` keeps each primitive's identity.
    #[test]
    fn mesh_triangles_read_their_vertices_from_the_mesh() {
        let meshes = [mesh(), mesh()];
        let mut a = Primitives::new();
        a.push(Primitive { shape: Shape::Sphere(Sphere::new(Vec3::Z, 0.5)), material: 7, light: 3 });
        a.push_mesh(1, 4, [1u32].into_iter());
        let mut b = Primitives::new();
        b.push_mesh(0, 5, [0u32, 1].into_iter());
        b.push(Primitive { shape: Shape::Sphere(Sphere::new(Vec3::X, 2.0)), material: 8, light: NO_LIGHT });
        a.append(b);
        assert_eq!(a.len(), 5);
        assert_eq!(a.material_light(0), (7, 3));
        assert_eq!(a.material_light(1), (4, NO_LIGHT));
        assert_eq!(a.material_light(3), (5, NO_LIGHT));
        assert_eq!(a.material_light(4), (8, NO_LIGHT));
        let Shape::Triangle(t) = a.get(1, &meshes).shape else { panic!("not a triangle") };
        assert_eq!((t.p, t.mesh, t.index), ([Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y], 1, 1));
        let Shape::Triangle(t) = a.get(2, &meshes).shape else { panic!("not a triangle") };
        assert_eq!((t.p, t.mesh, t.index), ([Vec3::ZERO, Vec3::X, Vec3::Y], 0, 0));
        assert_eq!(a.bounds(4, &meshes).max, Vec3::new(3.0, 2.0, 2.0));
        // Reordering moves whole primitives.
        a.reorder(&[4, 2, 0, 1, 3]);
        assert_eq!(a.material_light(0), (8, NO_LIGHT));
        assert_eq!(a.material_light(2), (7, 3));
        let Shape::Triangle(t) = a.get(4, &meshes).shape else { panic!("not a triangle") };
        assert_eq!((t.mesh, t.index), (0, 1));
    }
}
