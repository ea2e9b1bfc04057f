//! Criterion benchmarks of the light-tree build (PLOC) on seeded random
//! lights. Run with `cargo bench --bench tree`; `lightcuts bench tree` prints
//! the figures (sizes up to 4M, memory, quality against greedy).

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use lightcuts::cli::bench::tree::{random_lights, Distribution};
use lightcuts::light::LightKind;
use lightcuts::light_tree::ploc;

fn build(c: &mut Criterion) {
    let mut group = c.benchmark_group("ploc_build");
    group.sample_size(10);
    for kind in LightKind::ALL {
        for n in [10_000usize, 100_000] {
            let lights = random_lights(kind, n, Distribution::Clustered, 1);
            group.throughput(Throughput::Elements(n as u64));
            group.bench_with_input(BenchmarkId::new(kind.name(), n), &lights, |b, lights| {
                b.iter(|| ploc::build(kind, lights, 1));
            });
        }
    }
    group.finish();
}

criterion_group!(benches, build);
criterion_main!(benches);
