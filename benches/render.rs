//! `cargo bench`: BVH build, primary rays through the BVH on the 100k-triangle mesh scene, and a
//! full Whitted render. `caustic bench` prints the same figures as rays per second.

use caustic::accel::Bvh;
use caustic::bench::{MESH_SCENE, WHITTED_SCENE, load, primary_rays, whitted_render};
use caustic::shape::{Primitive, Shape, TriangleMesh};

fn main() {
    divan::main();
}

#[divan::bench(sample_count = 10)]
fn bvh_build_100k_triangles(bencher: divan::Bencher) {
    let mesh = TriangleMesh::torus_knot(2, 3, 1.0, 0.28, 1600, 32);
    let prims: Vec<Primitive> = mesh
        .triangles(0)
        .0
        .into_iter()
        .map(|t| Primitive { shape: Shape::Triangle(t), material: 0, light: caustic::geometry::NO_LIGHT })
        .collect();
    bencher.bench(|| Bvh::build(divan::black_box(prims.clone()), &[]));
}

#[divan::bench(sample_count = 10)]
fn primary_rays_mesh_1m(bencher: divan::Bencher) {
    let scene = load(MESH_SCENE, "mesh");
    bencher.bench(|| primary_rays(divan::black_box(&scene)));
}

#[divan::bench(sample_count = 5)]
fn whitted_512_16spp(bencher: divan::Bencher) {
    let scene = load(WHITTED_SCENE, "whitted");
    bencher.bench(|| whitted_render(divan::black_box(&scene)));
}
