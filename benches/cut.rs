//! Criterion benchmarks of the lightcut at a fixed set of shading points
//! (the first hits of a 64x48 image of grid10k): the whole cut at 2% and
//! 0.5%, and its parts alone: the bounds of every block of the tree at one
//! point, and one light's M * G and shadow ray. Run with
//! `cargo bench --bench cut`.

use criterion::{criterion_group, criterion_main, Criterion};
use lightcuts::embree::Device;
use lightcuts::light::Lights;
use lightcuts::lightcut::bounds::PointBounds;
use lightcuts::lightcut::{evaluate, CutScratch, CutSettings};
use lightcuts::scene::Scene;
use lightcuts::shading::light_sample;
use lightcuts::shading::Geometry;

fn cut(c: &mut Criterion) {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/grid10k.toml");
    let scene = Scene::load(&path).expect("scenes/grid10k.toml loads");
    let device = Device::try_new().expect("Embree device");
    let lights = Lights::from_scene(&scene);
    let geometry = Geometry::try_new(&device, &scene, std::slice::from_ref(&lights)).expect("geometry");
    let trees = lightcuts::lightcut::build_trees(std::slice::from_ref(&lights), 0);
    let camera = scene.camera(64, 48);
    let points: Vec<_> = (0..48)
        .flat_map(|y| (0..64).map(move |x| (x, y)))
        .filter_map(|(x, y)| {
            let ray = camera.ray(x as f32 + 0.5, y as f32 + 0.5);
            geometry.embree.intersect(&ray).map(|hit| geometry.surface(&ray, &hit))
        })
        .collect();
    let mut group = c.benchmark_group("lightcut");
    group.sample_size(10);
    for error in [0.02, 0.005] {
        let settings = CutSettings { error, max_cut: 1000, ..CutSettings::default() };
        group.bench_function(format!("grid10k_{}_points_error_{error}", points.len()), |b| {
            let mut scratch = CutScratch::default();
            b.iter(|| {
                let mut nodes = 0;
                for sp in &points {
                    nodes +=
                        std::hint::black_box(evaluate(&trees, sp, &geometry.embree, &settings, &mut scratch, 0)).nodes;
                }
                nodes
            });
        });
    }
    let tree = &trees.trees[0];
    let sp = &points[points.len() / 2];
    group.bench_function(format!("bounds_of_{}_blocks", tree.blocks.len()), |b| {
        b.iter(|| {
            let bounds = PointBounds::new(sp, trees.scale);
            tree.blocks.iter().map(|block| bounds.pair(tree.kind, block, None)[1]).sum::<f32>()
        });
    });
    group.bench_function(format!("light_sample_of_{}_lights", tree.blocks.len()), |b| {
        b.iter(|| {
            (1..tree.blocks.len())
                .filter_map(|k| light_sample(&tree.representative(k, 1).light(tree.kind), sp, glam::Vec3::ONE))
                .count()
        });
    });
    group.finish();
}

criterion_group!(benches, cut);
criterion_main!(benches);
