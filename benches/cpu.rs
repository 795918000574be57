//! The CPU work a GPU frame waits on, on oa_dm1 (7.5k world triangles, four lights): loading
//! the BSP, building caster groups and one light's volumes, planning frames along the scene's
//! flythrough, building the reference's BVH and tracing shadow rays through it.
//!
//! `cargo bench --bench cpu`; baselines and how to compare against them: docs/benchmarks.md.
//! Needs OpenArena's data (`scripts/fetch-openarena.sh`).

use criterion::{BatchSize, Criterion, Throughput, criterion_group, criterion_main};
use glam::{DVec3, Vec3};
use shadowlab::options::Options;
use shadowlab::plan::planner::Planner;
use shadowlab::plan::volume_draws::settings;
use shadowlab::q3::pk3::{Vfs, data_dir};
use shadowlab::scene::path;
use shadowlab::scene::{Camera, Scene, SurfaceOwner};
use shadowlab::shadow::volume::{CasterGroups, build_volume};
use shadowlab::truth::reference::{Reference, shadow_ray_origin};
use std::hint::black_box;
use std::path::Path;

const SCENE: &str = "assets/scenes/oa_dm1.toml";
const MAP: &str = "maps/oa_dm1.bsp";
/// Shadow rays per iteration of the ray benchmark.
const RAYS: usize = 4096;

struct Loaded {
    scene: Scene,
    options: Options,
    flythrough: Vec<Camera>,
    bsp: Vec<u8>,
}

fn load() -> Loaded {
    let fetch = "run `scripts/fetch-openarena.sh` first: these benchmarks use OpenArena's oa_dm1";
    let vfs = Vfs::open_data_dir(&data_dir()).unwrap_or_else(|e| panic!("{e}\n{fetch}"));
    let bsp = vfs
        .read(MAP)
        .unwrap_or_else(|e| panic!("{MAP}: {e}\n{fetch}"));
    let file = Path::new(env!("CARGO_MANIFEST_DIR")).join(SCENE);
    let loaded = shadowlab::scene_file::load::load_file_over(Options::default(), &file, |mut o| {
        o.q3.progress = false;
        Ok::<_, std::convert::Infallible>(o)
    })
    .unwrap_or_else(|e| panic!("{SCENE}: {e}\n{fetch}"));
    let keys = loaded
        .report
        .flythrough
        .as_deref()
        .map(|p| path::read(p).unwrap_or_else(|e| panic!("{}: {e}", p.display())))
        .unwrap_or_else(|| panic!("{SCENE} names no flythrough"));
    let scene = loaded.scene;
    let flythrough = keys.iter().map(|k| k.apply(&scene.camera)).collect();
    Loaded {
        flythrough,
        options: loaded.options,
        scene,
        bsp,
    }
}

/// Shadow rays from surface points spread over the scene's triangles to the nearest light.
fn rays(scene: &Scene) -> Vec<(DVec3, DVec3)> {
    let triangles = scene.indices.len() / 3;
    let step = (triangles / RAYS).max(1);
    (0..triangles)
        .step_by(step)
        .take(RAYS)
        .map(|t| {
            let v = |i: usize| &scene.vertices[scene.indices[3 * t + i] as usize];
            let p =
                (Vec3::from(v(0).position) + Vec3::from(v(1).position) + Vec3::from(v(2).position))
                    / 3.0;
            let light = scene
                .lights
                .iter()
                .min_by(|a, b| a.position.distance(p).total_cmp(&b.position.distance(p)))
                .expect("oa_dm1 has lights")
                .position;
            (
                shadow_ray_origin(p, Vec3::from(v(0).normal)),
                light.as_dvec3(),
            )
        })
        .collect()
}

fn benches(c: &mut Criterion) {
    let loaded = load();
    let scene = &loaded.scene;
    let options = &loaded.options;

    c.bench_function("bsp_parse", |b| {
        b.iter(|| shadowlab::q3::bsp::parse(black_box(&loaded.bsp)).expect("oa_dm1 parses"))
    });

    c.bench_function("caster_groups", |b| {
        b.iter(|| CasterGroups::build(black_box(scene)))
    });

    let groups = CasterGroups::build(scene);
    let world = groups
        .groups
        .iter()
        .find(|g| g.owner == SurfaceOwner::World)
        .expect("oa_dm1 has a world");
    let light = scene.lights[0].position.as_dvec3();
    let s = settings(&options.shadow_volume);
    c.bench_function("volume_build_light0_world", |b| {
        b.iter(|| {
            (0..world.components.len())
                .map(|i| build_volume(world, i, light, &s, true).vertices.len())
                .sum::<usize>()
        })
    });

    // A warm planner (caster groups built, frusta kept) on a moving camera: each iteration plans
    // the next key of the flythrough, as a walkthrough would.
    let mut group = c.benchmark_group("plan");
    group.throughput(Throughput::Elements(1));
    group.bench_function("flythrough_frame", |b| {
        let mut planner = Planner::default();
        let mut frame = 0;
        b.iter(|| {
            let camera = &loaded.flythrough[frame % loaded.flythrough.len()];
            frame += 1;
            planner.plan(scene, camera, options)
        })
    });
    group.bench_function("cold_first_frame", |b| {
        b.iter_batched(
            Planner::default,
            |mut planner| planner.plan(scene, &loaded.flythrough[0], options),
            BatchSize::PerIteration,
        )
    });
    group.finish();

    let mut group = c.benchmark_group("reference");
    group.sample_size(10);
    group.bench_function("bvh_build", |b| {
        b.iter(|| Reference::build(black_box(scene)))
    });
    let reference = Reference::build(scene);
    let rays = rays(scene);
    group.throughput(Throughput::Elements(rays.len() as u64));
    group.bench_function("shadow_rays", |b| {
        b.iter(|| {
            rays.iter()
                .filter(|(from, to)| reference.occluded(*from, *to))
                .count()
        })
    });
    group.finish();
}

criterion_group!(cpu, benches);
criterion_main!(cpu);
