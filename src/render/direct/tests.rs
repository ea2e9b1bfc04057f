//! The interface from outside: a method that no renderer ships, uniform
//! light sampling, written against [`DirectLight`] alone (no other file
//! changes for it), checked unbiased against the exact method.

use super::{exact::Exact, DirectLight, DirectWorker, Vertex};
use crate::embree::Device;
use crate::light::{Light, Lights};
use crate::lightcut::CutResult;
use crate::render::integrator::Integrator;
use crate::render::stats::ShadingStats;
use crate::render::tracer::Tracer;
use crate::render::{render, Aovs, PassSettings, PixelBounds, TextureFilter};
use crate::shading::{BatchBuffers, Geometry, LightBatch};
use crate::util::streams::Stream;

// ---- The method: 33 lines of code, 38 with its comments. ----

/// One light drawn uniformly from all of them at each vertex, its light
/// divided by its probability: an unbiased estimate of the exact sum.
/// `weight` is 1 / probability (the number of lights); a wrong one is
/// the bias the test below must see.
struct Uniform {
    lights: Vec<(usize, Light)>,
    weight: f64,
}

impl<'a> DirectLight<'a> for Uniform {
    fn worker<'m>(&'m self) -> Box<dyn DirectWorker<'a> + 'm>
    where
        'a: 'm,
    {
        Box::new(UniformWorker { method: self, batch: BatchBuffers::default() })
    }
}

struct UniformWorker<'m> {
    method: &'m Uniform,
    batch: BatchBuffers,
}

impl<'a> DirectWorker<'a> for UniformWorker<'_> {
    fn light(&mut self, tracer: &Tracer<'a>, vertex: &Vertex<'_, 'a>, _: &mut ShadingStats) -> Option<CutResult> {
        let mut found = CutResult::with_groups(tracer.group_slots());
        let [seed, x, y, s] = vertex.sample;
        // The direct-light method's stream (one method a pass).
        let u = Stream::Stochastic.rng(&[seed, x, y, s, u64::from(vertex.depth)]).next_f64();
        let lights = &self.method.lights;
        let Some(&(group, light)) = lights.get(((u * lights.len() as f64) as usize).min(lights.len() - 1)) else {
            return Some(found);
        };
        let mut batch = LightBatch::new(&tracer.geometry.embree, vertex.sp, &mut self.batch);
        batch.add(&light);
        let mut batch = batch.finish();
        batch.radiance *= self.method.weight;
        found.radiance = found.count_batch(group, &batch);
        Some(found)
    }
}

// ---- The check. ----

/// Samples a pixel of the check's renders.
const SPP: u32 = 64;

/// The beauty's red, green and blue summed, pixel by pixel, of a 48 x 36
/// window of the floor, spheres and 16 point lights scene, at [`SPP`]
/// samples a pixel, lit by `direct`.
fn beauty<M: for<'a> DirectLight<'a> + 'static>(
    direct: &M,
    scene: &crate::scene::Scene,
    lights: &[Lights],
) -> Vec<f64> {
    let device = Device::try_new().unwrap();
    let geometry = Geometry::try_new(&device, scene, lights).unwrap();
    let (width, height) = (scene.film.width, scene.film.height);
    let camera = scene.camera(width, height);
    let settings = PassSettings {
        width,
        height,
        spp: SPP,
        seed: 3,
        bounds: PixelBounds { x0: 24, x1: 72, y0: 20, y1: 56 },
        aovs: Aovs { groups: false, ..Aovs::all(false) },
        transparent: false,
        texture_filter: TextureFilter::Mip,
    };
    let emission_group = scene.emission_groups();
    let integrator = Integrator {
        tracer: Tracer { geometry: &geometry, lights, split_groups: false, emitters: None, spp: SPP, footprint: None },
        direct,
        max_mirror_depth: scene.max_mirror_depth,
        emission_group: &emission_group,
        path_depth: None,
    };
    let (film, _) = render(&integrator, &camera, &settings, &|_| {}).unwrap();
    let channel = |name: &str| &film.channels.iter().find(|c| c.name == name).unwrap().values;
    let (r, g, b) = (channel("R"), channel("G"), channel("B"));
    (0..r.len()).map(|i| f64::from(r[i]) + f64::from(g[i]) + f64::from(b[i])).collect()
}

/// The mean of `a - b` over the pixels, and its standard error.
fn mean_difference(a: &[f64], b: &[f64]) -> (f64, f64) {
    let n = a.len() as f64;
    let d: Vec<f64> = a.iter().zip(b).map(|(x, y)| x - y).collect();
    let mean = d.iter().sum::<f64>() / n;
    let variance = d.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / (n - 1.0);
    (mean, (variance / n).sqrt())
}

#[test]
fn uniform_light_sampling_through_the_interface_is_unbiased() {
    let scene = crate::scene::builder::floor_spheres_grid(4).load(std::path::Path::new("uniform.toml")).unwrap();
    let lights = Lights::by_group(&scene);
    let mut all = Vec::new();
    for (g, group) in lights.iter().enumerate() {
        group.for_each(|light| all.push((g, light)));
    }
    assert_eq!(all.len(), 16);
    let exact = beauty(&Exact, &scene, &lights);
    let mean_exact = exact.iter().sum::<f64>() / exact.len() as f64;
    assert!(mean_exact > 0.01, "the window is lit: {mean_exact}");
    // The same camera samples (same seed), each vertex lit by one light:
    // the pixels differ by the light's choice alone, whose mean is 0.
    let uniform = beauty(&Uniform { lights: all.clone(), weight: 16.0 }, &scene, &lights);
    assert_ne!(uniform, exact, "one light a vertex is noisier than all of them");
    let (mean, error) = mean_difference(&uniform, &exact);
    assert!(mean.abs() < 4.0 * error, "biased: mean difference {mean} (standard error {error})");
    assert!(error < 0.01 * mean_exact, "the check resolves a 6% bias: standard error {error} of {mean_exact}");
    // The check can fail: weighing each light as one of 15 is 6.25% low.
    let low = beauty(&Uniform { lights: all, weight: 15.0 }, &scene, &lights);
    let (mean, error) = mean_difference(&low, &exact);
    assert!(mean.abs() > 4.0 * error, "a 6.25% bias went unseen: {mean} (standard error {error})");
}
