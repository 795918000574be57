//! The planner's decisions on small hand-built scenes, without GL (issue 18): which caster
//! pieces get volume parts, how each is counted, the rectangles parts are scissored to, which
//! chunks are merged, the depth clip fitted to a hand-made depth buffer, and the keys by which
//! caster groups, depths and volume draws are reused.
//!
//! Every scene is a floor (receives light, casts no shadow) under boxes (cast shadows, receive
//! no light), so the only receiver box is the floor's and every number below can be worked out
//! by hand. Each test states what it guards; most also check the switch off, so a decision that
//! stopped being made would fail them. Each was seen to fail with the condition it guards
//! broken in `src/plan` (then restored).

use glam::{Mat4, Vec3};
use shadowlab::geometry::Aabb;
use shadowlab::options::{Options, Technique};
use shadowlab::plan::occlusion::DepthPyramid;
use shadowlab::plan::planner::{DepthNeed, Planner};
use shadowlab::plan::scissor::{Scissor, points_scissor};
use shadowlab::plan::volume_draws::{PartRange, PieceId, Span, VolumeDraw, VolumeStats};
use shadowlab::plan::{LightPlan, PartTriangles, Plan, VolumePart};
use shadowlab::scene::shapes::{MeshData, cuboid};
use shadowlab::scene::{
    AlphaFunc, Camera, Light, Material, ModelInstance, Scene, SurfaceKind, SurfaceOwner,
};
use shadowlab::shadow::volume::{
    CHUNK_TRIANGLES, CasterGroups, ChunkNode, Counting, PieceRef, shadow_bounds,
};
use std::sync::Arc;

// ---------------------------------------------------------------------------------------------
// Scenes and options

const WIDTH: usize = 640;
const HEIGHT: usize = 480;

/// Every planner switch the tests depend on, set explicitly (defaults may change), then `sets`.
/// The depth is not read (`occlusion`, `depth_clip` off) unless a test asks for it.
fn options(sets: &[&str]) -> Options {
    let mut o = Options::default();
    let base = [
        "technique=shadow_volume",
        "width=640",
        "height=480",
        "shadow_volume.counting=zfail",
        "shadow_volume.projection=infinite",
        "shadow_volume.caching=true",
        "plan.enabled=true",
        "plan.cull_lights=true",
        "plan.cull_receivers=true",
        "plan.cull_casters=true",
        "plan.scissor=true",
        "plan.piece_scissor=true",
        "plan.truncate_volumes=false",
        "plan.occlusion=false",
        "plan.reduce_depth=false",
        "plan.depth_clip=false",
        "plan.depth_clip_planes=4",
        "plan.reuse_depth_fits=true",
        "plan.reuse_depth=true",
        "plan.reuse_volume_draws=true",
        // Pieces fitted to the view (`plan.profile = software`'s choice); tests/kept_volumes.rs
        // holds the kept ones.
        "plan.keep_volumes=false",
        "plan.cull_clipped=false",
        "plan.merge_pieces=false",
        "plan.counting=true",
        "plan.near_plane_test=true",
        "plan.split_counting=false",
        "plan.one_pass_stencil=false",
    ];
    for s in base.iter().chain(sets) {
        o.set_assignment(s).unwrap_or_else(|e| panic!("{s}: {e}"));
    }
    o
}

/// Receives light, casts no shadow.
fn floor_material() -> Material {
    Material {
        casts_shadows: false,
        ..Material::opaque("floor", None)
    }
}

/// Casts shadows, receives no light (so the floor is the only receiver).
fn caster_material() -> Material {
    Material {
        receives_light: false,
        ..Material::opaque("caster", None)
    }
}

fn alpha_caster_material() -> Material {
    Material {
        alpha_test: Some(AlphaFunc::Ge128),
        ..caster_material()
    }
}

fn add(scene: &mut Scene, mesh: &MeshData, material: Material, owner: SurfaceOwner) {
    scene.materials.push(material);
    let m = scene.materials.len() - 1;
    scene.push_surface(&mesh.vertices, &mesh.indices, m, owner, SurfaceKind::Mesh);
}

/// A square of side `2 half` at height z, facing +Z.
fn floor_mesh(half: f32, z: f32) -> MeshData {
    let mut m = MeshData::default();
    m.quad(
        Vec3::new(-half, -half, z),
        Vec3::new(half, -half, z),
        Vec3::new(half, half, z),
        Vec3::new(-half, half, z),
        [1.0, 1.0],
    );
    m
}

/// A floor of side `2 half` at z = 0 and one omni light; no casters yet.
fn floor_scene(half: f32, light: Vec3, radius: f32) -> Scene {
    let mut scene = Scene::default();
    scene.name = "plan decisions".into();
    scene.lights = vec![Light::omni("light", light, radius)];
    add(
        &mut scene,
        &floor_mesh(half, 0.0),
        floor_material(),
        SurfaceOwner::World,
    );
    scene
}

fn add_box(scene: &mut Scene, min: Vec3, max: Vec3) {
    add(
        scene,
        &cuboid(min, max, 8.0),
        caster_material(),
        SurfaceOwner::World,
    );
}

/// Box A: 20×20×20 at 20..40 above a 200×200 floor, under an omni light at height 100 of
/// range 150. Its shadow box on the floor is x, y ∈ [-25, 25] (the corners pushed from the
/// light by 150 / 60).
const BOX_A: (Vec3, Vec3) = (Vec3::new(-10.0, -10.0, 20.0), Vec3::new(10.0, 10.0, 40.0));
const LIGHT: Vec3 = Vec3::new(0.0, 0.0, 100.0);
const RADIUS: f32 = 150.0;

fn between_scene() -> Scene {
    let mut scene = floor_scene(100.0, LIGHT, RADIUS);
    add_box(&mut scene, BOX_A.0, BOX_A.1);
    scene
}

/// Far off, looking down at the floor: outside the light's range box, nowhere near a shadow.
fn far_camera() -> Camera {
    Camera::looking_at(Vec3::new(600.0, 0.0, 300.0), Vec3::ZERO)
}

/// Under box A looking straight down: the near plane (z = 6) lies inside its shadow.
fn camera_in_shadow() -> Camera {
    Camera::looking_at(Vec3::new(0.0, 0.0, 10.0), Vec3::ZERO)
}

/// A plate of 16×16 quads (512 triangles, one welded component) over x, y ∈ [-20, 20] at
/// z = 40, facing up: more than CHUNK_TRIANGLES, so it is cut once, along x (the median of
/// its centroids), into chunk 0 (x < 0) and chunk 1 (x > 0).
fn plate_scene() -> Scene {
    const N: usize = 16;
    let p = |i: usize, j: usize| Vec3::new(-20.0 + 2.5 * i as f32, -20.0 + 2.5 * j as f32, 40.0);
    let mut plate = MeshData::default();
    for j in 0..N {
        for i in 0..N {
            plate.quad(
                p(i, j),
                p(i + 1, j),
                p(i + 1, j + 1),
                p(i, j + 1),
                [1.0, 1.0],
            );
        }
    }
    assert_eq!(plate.triangle_count(), 2 * N * N);
    let mut scene = floor_scene(100.0, LIGHT, RADIUS);
    add(&mut scene, &plate, caster_material(), SurfaceOwner::World);
    scene
}

// ---------------------------------------------------------------------------------------------
// Running the planner

fn plan(scene: &Scene, camera: &Camera, o: &Options) -> Plan {
    Plan::build_at(scene, camera, o)
}

/// The plan of light 0, which must run shadow volumes.
fn light0(plan: &Plan) -> &LightPlan {
    let lp = plan
        .lights
        .iter()
        .find(|l| l.light == 0)
        .unwrap_or_else(|| panic!("light 0 culled: {:?}", plan.stats));
    assert_eq!(lp.technique, Technique::ShadowVolume, "{}", lp.reason);
    lp
}

/// The bounds of the piece a planned part is extruded from.
fn piece_bounds(groups: &CasterGroups, part: &VolumePart) -> Aabb {
    groups.groups[part.group].piece(part.piece).bounds
}

/// The centres of the pieces light 0's parts are extruded from.
fn part_centres(scene: &Scene, plan: &Plan) -> Vec<Vec3> {
    let groups = CasterGroups::build(scene);
    light0(plan)
        .volumes
        .iter()
        .map(|p| piece_bounds(&groups, p).center())
        .collect()
}

/// A depth buffer holding `depth` everywhere (every pixel shows a surface).
fn flat_depth(depth: f32) -> DepthPyramid {
    DepthPyramid::from_top_down(&vec![depth; WIDTH * HEIGHT], WIDTH, HEIGHT).unwrap()
}

/// What one frame decided for light 0's volumes.
struct Frame {
    plan: Plan,
    need: DepthNeed,
    parts: Vec<PartRange>,
    draws: Vec<VolumeDraw>,
    stats: VolumeStats,
    uploads_vertices: bool,
}

/// One frame as the renderer runs it, without GL: plan, ask what depth is needed, hand over
/// a flat depth buffer of `depth` when it is to be read, then light 0's volume draws.
fn frame(
    planner: &mut Planner,
    scene: &Scene,
    camera: &Camera,
    o: &Options,
    depth: Option<f32>,
) -> Frame {
    let plan = planner.plan(scene, camera, o);
    let need = planner.depth_need(scene, &plan, o, false);
    if let (DepthNeed::Read { .. }, Some(d)) = (need, depth) {
        planner.take_depth(Some(flat_depth(d)), o);
    }
    let lp = light0(&plan).clone();
    let lv = planner
        .volume_draws(scene, &plan, &lp, o)
        .unwrap_or_else(|e| panic!("{e}"));
    Frame {
        parts: lv.parts.clone(),
        draws: lv.draws.clone(),
        stats: lv.stats,
        uploads_vertices: lv.upload.spans.is_some(),
        plan,
        need,
    }
}

fn countings(lp: &LightPlan) -> Vec<(Counting, PartTriangles)> {
    lp.volumes
        .iter()
        .map(|v| (v.counting, v.triangles))
        .collect()
}

const NO_CLIP: [[f32; 4]; 4] = [[0.0; 4]; 4];

// ---------------------------------------------------------------------------------------------
// Pieces

/// Guards the range test of `plan.cull_casters`. A box 1000 units off would be culled by the
/// receiver test too (its shadow box is clipped to the light's range box, so it is empty); the
/// box at (115..135, 115..135, -10..10) is inside the range *box* (its shadow box is itself and
/// crosses the floor's) but 186 from the light, beyond the radius of 150: only the range test
/// drops it. Without the switch all three boxes get a part.
#[test]
fn a_box_outside_the_lights_range_gets_no_part() {
    let mut scene = floor_scene(200.0, LIGHT, RADIUS);
    add_box(&mut scene, BOX_A.0, BOX_A.1);
    add_box(
        &mut scene,
        Vec3::new(990.0, -10.0, 20.0),
        Vec3::new(1010.0, 10.0, 40.0),
    );
    let corner = (
        Vec3::new(115.0, 115.0, -10.0),
        Vec3::new(135.0, 135.0, 10.0),
    );
    add_box(&mut scene, corner.0, corner.1);
    assert!(LIGHT.distance(Vec3::new(115.0, 115.0, 10.0)) > RADIUS);
    let o = options(&[]);
    let p = plan(&scene, &far_camera(), &o);
    assert_eq!(part_centres(&scene, &p), vec![Vec3::new(0.0, 0.0, 30.0)]);
    assert!(
        light0(&p)
            .volumes
            .iter()
            .all(|v| matches!(v.piece, PieceRef::Chunk(_)))
    );
    assert_eq!((p.stats.casters_drawn, p.stats.casters_culled), (1, 2));

    let p = plan(
        &scene,
        &far_camera(),
        &options(&["plan.cull_casters=false"]),
    );
    assert_eq!(light0(&p).volumes.len(), 3);
    assert_eq!(p.stats.casters_culled, 0);
}

/// Guards the receiver test of `plan.cull_casters` (Forsyth): a box above the light, within its
/// range, throws its shadow upwards (z ≥ 110), where no receiver is (the floor's box is z = 0):
/// no part. A light whose only caster is that box has no shadow work at all.
#[test]
fn a_box_whose_shadow_misses_every_receiver_gets_no_part() {
    let above = (Vec3::new(-5.0, -5.0, 110.0), Vec3::new(5.0, 5.0, 120.0));
    let mut scene = between_scene();
    add_box(&mut scene, above.0, above.1);
    let o = options(&[]);
    let p = plan(&scene, &far_camera(), &o);
    assert_eq!(part_centres(&scene, &p), vec![Vec3::new(0.0, 0.0, 30.0)]);
    assert_eq!((p.stats.casters_drawn, p.stats.casters_culled), (1, 1));

    // The box alone: the light is left without shadow work, and says why.
    let mut alone = floor_scene(100.0, LIGHT, RADIUS);
    add_box(&mut alone, above.0, above.1);
    let p = plan(&alone, &far_camera(), &o);
    assert_eq!(p.lights.len(), 1);
    assert_eq!(p.lights[0].technique, Technique::None);
    assert!(p.lights[0].volumes.is_empty());
    assert_eq!(p.stats.lights_without_casters, 1);

    // Without caster culling it is extruded (guards against the test passing vacuously).
    let p = plan(
        &alone,
        &far_camera(),
        &options(&["plan.cull_casters=false"]),
    );
    assert_eq!(light0(&p).volumes.len(), 1);
}

/// Guards the paper's frame (`plan.enabled = false`): every component is extruded whole
/// (`PieceRef::Component`, all triangles), none is culled (the far box and the box above the light
/// included) and each counts depth-fail as `shadow_volume.counting = zfail` says. The planner's
/// frame on the same scene keeps one chunk.
#[test]
fn the_papers_frame_extrudes_whole_components() {
    let mut scene = between_scene();
    add_box(
        &mut scene,
        Vec3::new(990.0, -10.0, 20.0),
        Vec3::new(1010.0, 10.0, 40.0),
    );
    add_box(
        &mut scene,
        Vec3::new(-5.0, -5.0, 110.0),
        Vec3::new(5.0, 5.0, 120.0),
    );
    let groups = CasterGroups::build(&scene);
    assert_eq!(groups.groups.len(), 1);
    assert_eq!(groups.groups[0].components.len(), 3);

    let p = plan(&scene, &far_camera(), &options(&["plan.enabled=false"]));
    let lp = light0(&p);
    let mut components: Vec<usize> = lp
        .volumes
        .iter()
        .map(|v| match v.piece {
            PieceRef::Component(i) => i,
            PieceRef::Chunk(_) => panic!("{v:?} is a chunk"),
        })
        .collect();
    components.sort_unstable();
    assert_eq!(components, vec![0, 1, 2]);
    for v in &lp.volumes {
        assert!(matches!(v.piece, PieceRef::Component(_)), "{v:?}");
        assert_eq!(
            (v.counting, v.triangles),
            (Counting::ZFail, PartTriangles::All)
        );
    }
    assert!(lp.volume_receivers.is_empty());
    assert_eq!(lp.scissor, None);
    assert_eq!((p.stats.zfail_parts, p.stats.zpass_parts), (3, 0));

    let p = plan(&scene, &far_camera(), &options(&[]));
    assert_eq!(light0(&p).volumes.len(), 1);
    assert!(matches!(light0(&p).volumes[0].piece, PieceRef::Chunk(_)));
}

// ---------------------------------------------------------------------------------------------
// Counting

/// Guards Doom 3's test as the planner applies it: with the camera far from box A's shadow
/// (neither the eye nor the light in its box grown by 2 near, and the segment between them
/// above it), box A counts depth-pass; under `counting = zfail` without `plan.counting` it
/// stays depth-fail.
#[test]
fn a_camera_far_from_the_shadow_counts_depth_pass() {
    let scene = between_scene();
    let p = plan(&scene, &far_camera(), &options(&[]));
    assert_eq!(
        countings(light0(&p)),
        vec![(Counting::ZPass, PartTriangles::All)]
    );
    let s = &p.stats;
    assert_eq!((s.zpass_parts, s.zfail_parts, s.split_parts), (1, 0, 0));

    let p = plan(&scene, &far_camera(), &options(&["plan.counting=false"]));
    assert_eq!(
        countings(light0(&p)),
        vec![(Counting::ZFail, PartTriangles::All)]
    );
    assert_eq!((p.stats.zpass_parts, p.stats.zfail_parts), (0, 1));
}

/// Guards the depth-fail choice: with the near plane inside box A's shadow, box A counts
/// depth-fail, by the box test alone (`near_plane_test` off) and by the near-plane test (its
/// top face's triangles meet the hull of the light and the near-plane rectangle).
#[test]
fn a_camera_inside_the_shadow_counts_depth_fail() {
    let scene = between_scene();
    for near_plane_test in ["false", "true"] {
        let o = options(&[&format!("plan.near_plane_test={near_plane_test}")]);
        let p = plan(&scene, &camera_in_shadow(), &o);
        let lp = light0(&p);
        assert_eq!(
            countings(lp),
            vec![(Counting::ZFail, PartTriangles::All)],
            "near_plane_test={near_plane_test}"
        );
        assert!(lp.near_plane_triangles.is_empty());
        let s = &p.stats;
        assert_eq!((s.zpass_parts, s.zfail_parts, s.split_parts), (0, 1, 0));
    }
}

/// Guards `plan.split_counting`: box A with the near plane in its shadow is split into its
/// facing triangles near the near plane (the two of its top face, z = 40: the only faces facing
/// a light straight above), depth-fail, and the rest, depth-pass; each counted once in the
/// stats' parts and once as a split.
#[test]
fn split_counting_splits_off_the_triangles_over_the_near_plane() {
    let scene = between_scene();
    let p = plan(
        &scene,
        &camera_in_shadow(),
        // The paper's casting: cast from both sides, the bottom face's two triangles shadow
        // the near plane too.
        &options(&["plan.split_counting=true", "shadow_volume.casters=front"]),
    );
    let lp = light0(&p);
    assert_eq!(
        countings(lp),
        vec![
            (Counting::ZFail, PartTriangles::NearPlane(0)),
            (Counting::ZPass, PartTriangles::Rest(0)),
        ]
    );
    assert_eq!(lp.volumes[0].piece, lp.volumes[1].piece);
    assert_eq!(lp.near_plane_triangles.len(), 1);
    let near = &lp.near_plane_triangles[0];
    assert_eq!(near.len(), 2, "{near:?}");
    assert!(near.windows(2).all(|w| w[0] < w[1]), "sorted: {near:?}");
    let groups = CasterGroups::build(&scene);
    let c = &groups.groups[lp.volumes[0].group].connectivity;
    for &t in near {
        for v in c.triangles[t as usize] {
            assert_eq!(
                c.positions[v as usize].z, 40.0,
                "triangle {t} is not the top face"
            );
        }
    }
    let s = &p.stats;
    assert_eq!((s.zpass_parts, s.zfail_parts, s.split_parts), (1, 1, 1));

    // The far camera: nothing to split.
    let p = plan(
        &scene,
        &far_camera(),
        &options(&["plan.split_counting=true"]),
    );
    assert_eq!(
        countings(light0(&p)),
        vec![(Counting::ZPass, PartTriangles::All)]
    );
    assert_eq!(p.stats.split_parts, 0);
}

/// Guards the alpha-tested exception: the far camera would count box A depth-pass, but an
/// alpha-tested box A counts depth-fail (a ray through its holes enters the volume through the
/// front cap).
#[test]
fn an_alpha_tested_caster_counts_depth_fail() {
    let mut scene = floor_scene(100.0, LIGHT, RADIUS);
    add(
        &mut scene,
        &cuboid(BOX_A.0, BOX_A.1, 8.0),
        alpha_caster_material(),
        SurfaceOwner::World,
    );
    let p = plan(&scene, &far_camera(), &options(&[]));
    assert_eq!(
        countings(light0(&p)),
        vec![(Counting::ZFail, PartTriangles::All)]
    );
    let s = &p.stats;
    assert_eq!((s.zpass_parts, s.zfail_parts, s.split_parts), (0, 1, 0));
}

// ---------------------------------------------------------------------------------------------
// Rectangles

/// Guards `plan.piece_scissor`: box A's part is scissored to the screen rectangle of the floor's
/// box cut to box A's shadow box, inside the light's rectangle (not the whole screen, the
/// camera being far), and smaller than it. Without the switch the part has no rectangle of its
/// own.
#[test]
fn a_parts_rectangle_is_that_of_the_receivers_it_shadows() {
    let scene = between_scene();
    let camera = far_camera();
    let o = options(&[]);
    let mut planner = Planner::default();
    let f = frame(&mut planner, &scene, &camera, &o, None);
    assert_eq!(f.need, DepthNeed::None);
    let light_rect = light0(&f.plan).scissor.expect("the light's rectangle");
    let full = Scissor::full(&f.plan.camera);
    assert!(light_rect.area() < full.area(), "{light_rect:?}");

    let floor = scene.surfaces[0].bounds;
    let shadow = shadow_bounds(&Aabb::from_points([BOX_A.0, BOX_A.1]), LIGHT, RADIUS);
    assert_eq!(shadow.min.truncate(), glam::Vec2::splat(-25.0));
    assert_eq!(shadow.max.truncate(), glam::Vec2::splat(25.0));
    let expected = points_scissor(&f.plan.camera, &floor.intersection(&shadow).corners())
        .unwrap()
        .intersect(&light_rect);

    assert_eq!(f.parts.len(), 1);
    let part = f.parts[0];
    assert_eq!(part.scissor, Some(expected));
    let r = expected;
    assert!(
        r.area() > 0 && r.area() < light_rect.area() / 4,
        "{r:?} in {light_rect:?}"
    );
    assert!(r.x >= light_rect.x && r.y >= light_rect.y);
    assert!(r.x + r.width <= light_rect.x + light_rect.width);
    assert!(r.y + r.height <= light_rect.y + light_rect.height);
    assert!(part.drawn());
    assert_eq!(f.draws.len(), 1);
    assert_eq!(f.draws[0].scissor, Some(expected));
    assert_eq!(f.stats.parts_offscreen, 0);

    let f = frame(
        &mut Planner::default(),
        &scene,
        &camera,
        &options(&["plan.piece_scissor=false"]),
        None,
    );
    assert_eq!(f.parts[0].scissor, None);
    assert_eq!(f.stats.part_scissor_fraction, 1.0);
}

/// A 600×600 floor under an omni light at (0, 40, 200) of range 400, and a camera at height
/// 60 looking level along +Y: it sees the floor only beyond y = 80 (the lower edge of its view
/// falls at 36.87°, tan = 0.75), and nothing behind y = 4 (its near plane).
const LEVEL_LIGHT: Vec3 = Vec3::new(0.0, 40.0, 200.0);
const LEVEL_RADIUS: f32 = 400.0;

fn level_scene() -> (Scene, Camera) {
    let scene = floor_scene(300.0, LEVEL_LIGHT, LEVEL_RADIUS);
    let camera = Camera::looking_at(Vec3::new(0.0, 0.0, 60.0), Vec3::new(0.0, 100.0, 60.0));
    (scene, camera)
}

/// Box A of the level scene: its shadow lands on the floor at y ≥ 145, in view.
const LEVEL_BOX_A: (Vec3, Vec3) = (Vec3::new(-5.0, 145.0, 100.0), Vec3::new(5.0, 155.0, 120.0));

/// Guards the view test of `plan.cull_casters`: a box behind the camera (y ∈ [-60, -40]) whose
/// shadow, thrown away from the light at y = 40, stays behind it (its shadow box ends at
/// y = -40) gets no part, though that shadow box crosses the floor's. Without the switch it
/// gets one.
#[test]
fn a_box_whose_shadow_is_out_of_view_gets_no_part() {
    let (mut scene, camera) = level_scene();
    add_box(&mut scene, LEVEL_BOX_A.0, LEVEL_BOX_A.1);
    let behind = (Vec3::new(-5.0, -60.0, 100.0), Vec3::new(5.0, -40.0, 120.0));
    add_box(&mut scene, behind.0, behind.1);
    let shadow = shadow_bounds(
        &Aabb::from_points([behind.0, behind.1]),
        LEVEL_LIGHT,
        LEVEL_RADIUS,
    );
    assert_eq!(shadow.max.y, -40.0);
    assert!(shadow.intersects(&scene.surfaces[0].bounds));

    let p = plan(&scene, &camera, &options(&[]));
    assert_eq!(part_centres(&scene, &p), vec![Vec3::new(0.0, 150.0, 110.0)]);
    assert_eq!(p.stats.casters_culled, 1);

    let p = plan(&scene, &camera, &options(&["plan.cull_casters=false"]));
    assert_eq!(light0(&p).volumes.len(), 2);
}

/// Guards the off-screen part: box B's shadow box meets the view (so the planner keeps it) but
/// lands on the floor at y ∈ [15, 65], in front of the camera and below the screen: its part
/// gets an empty rectangle and is not drawn; box A's, at y ≥ 145, is drawn. Without
/// `plan.piece_scissor` both are drawn.
#[test]
fn a_part_whose_receivers_are_off_screen_is_not_drawn() {
    let (mut scene, camera) = level_scene();
    let box_b = (Vec3::new(-5.0, 35.0, 100.0), Vec3::new(5.0, 45.0, 120.0));
    add_box(&mut scene, box_b.0, box_b.1);
    add_box(&mut scene, LEVEL_BOX_A.0, LEVEL_BOX_A.1);
    let shadow_b = shadow_bounds(
        &Aabb::from_points([box_b.0, box_b.1]),
        LEVEL_LIGHT,
        LEVEL_RADIUS,
    );
    assert_eq!((shadow_b.min.y, shadow_b.max.y), (15.0, 65.0));

    let o = options(&[]);
    let f = frame(&mut Planner::default(), &scene, &camera, &o, None);
    assert_eq!(light0(&f.plan).volumes.len(), 2, "both boxes are kept");
    let groups = CasterGroups::build(&scene);
    let is_box_b = |p: &PartRange| match p.piece {
        PieceId::Chunks(c, _) => groups.groups[p.group].chunks[c].bounds.min == box_b.0,
        other => panic!("{other:?}"),
    };
    assert_eq!(f.parts.len(), 2);
    for p in &f.parts {
        if is_box_b(p) {
            assert_eq!(p.scissor, Some(Scissor::EMPTY));
            assert!(!p.drawn());
        } else {
            assert!(p.scissor.unwrap().area() > 0, "{p:?}");
            assert!(p.drawn());
        }
    }
    assert_eq!(f.stats.parts_offscreen, 1);
    assert_eq!(f.draws.len(), 1);
    assert_eq!(
        f.stats.zpass_parts, 2,
        "the off-screen part is still built and uploaded"
    );

    let o = options(&["plan.piece_scissor=false"]);
    let f = frame(&mut Planner::default(), &scene, &camera, &o, None);
    assert!(f.parts.iter().all(PartRange::drawn));
    assert_eq!(f.stats.parts_offscreen, 0);
}

// ---------------------------------------------------------------------------------------------
// Merges

/// Guards `plan.merge_pieces`: the plate's two chunks, both kept depth-pass with mirror-image
/// rectangles that touch (camera in the plane x = 0), are drawn as one piece; without the
/// switch, as two.
#[test]
fn adjacent_chunks_kept_alike_are_merged() {
    let scene = plate_scene();
    let groups = CasterGroups::build(&scene);
    let g = &groups.groups[0];
    assert_eq!(g.components.len(), 1);
    assert_eq!(g.components[0].triangles.len(), 2 * CHUNK_TRIANGLES);
    assert_eq!(g.chunks.len(), 2);
    assert_eq!(
        g.chunk_tree,
        vec![ChunkNode {
            first: 0,
            mid: 1,
            end: 2
        }]
    );
    assert!(g.chunks[0].bounds.max.x <= 0.0 && g.chunks[1].bounds.min.x >= 0.0);

    let camera = Camera::looking_at(Vec3::new(0.0, 600.0, 300.0), Vec3::ZERO);
    // The plate is open: by default its chunks keep the paper's depth-fail
    // (`plan.open_depth_fail`); the merge is tested with the switch off.
    let p = plan(&scene, &camera, &options(&["plan.merge_pieces=true"]));
    assert_eq!(
        countings(light0(&p)),
        vec![(Counting::ZFail, PartTriangles::All); 2]
    );
    let merge = options(&["plan.merge_pieces=true", "plan.open_depth_fail=false"]);
    let p = plan(&scene, &camera, &merge);
    assert_eq!(
        countings(light0(&p)),
        vec![(Counting::ZPass, PartTriangles::All); 2]
    );

    let f = frame(&mut Planner::default(), &scene, &camera, &merge, None);
    assert_eq!((f.stats.chunks_merged, f.stats.merged_parts), (2, 1));
    assert_eq!(f.parts.len(), 1);
    assert_eq!(f.parts[0].piece, PieceId::Chunks(0, 2));

    let f = frame(
        &mut Planner::default(),
        &scene,
        &camera,
        &options(&["plan.open_depth_fail=false"]),
        None,
    );
    assert_eq!((f.stats.chunks_merged, f.stats.merged_parts), (0, 0));
    let mut pieces: Vec<PieceId> = f.parts.iter().map(|p| p.piece).collect();
    pieces.sort_by_key(|p| format!("{p:?}"));
    assert_eq!(pieces, vec![PieceId::Chunks(0, 1), PieceId::Chunks(1, 2)]);
}

/// Guards the merge's "counted alike": the camera at (-10, 0, 15) looks at (20, 0, 0), its near
/// plane under the plate's x < 0 half. Chunk 0 counts depth-fail; chunk 1 depth-pass (its
/// facing triangles all lie at x ≥ 0, while the hull of the light and the near plane crosses
/// z = 40 at x ∈ [-5.3, -3.5]). Both are drawn (chunk 0's rectangle is the whole screen: its
/// shadow reaches behind the camera), so their rectangles would allow a merge: the counting
/// alone keeps them apart.
#[test]
fn chunks_counted_differently_are_not_merged() {
    let scene = plate_scene();
    let camera = Camera::looking_at(Vec3::new(-10.0, 0.0, 15.0), Vec3::new(20.0, 0.0, 0.0));
    // The plate is open: the switch lets its chunks count as the near plane allows.
    let o = options(&["plan.merge_pieces=true", "plan.open_depth_fail=false"]);
    let p = plan(&scene, &camera, &o);
    let mut by_chunk: Vec<(usize, Counting)> = light0(&p)
        .volumes
        .iter()
        .map(|v| match v.piece {
            PieceRef::Chunk(i) => (i, v.counting),
            PieceRef::Component(_) => panic!("{v:?} is not a chunk"),
        })
        .collect();
    by_chunk.sort_by_key(|v| v.0);
    assert_eq!(by_chunk, vec![(0, Counting::ZFail), (1, Counting::ZPass)]);

    let f = frame(&mut Planner::default(), &scene, &camera, &o, None);
    assert_eq!((f.stats.chunks_merged, f.stats.merged_parts), (0, 0));
    assert_eq!(f.parts.len(), 2);
    assert!(f.parts.iter().all(PartRange::drawn), "{:?}", f.parts);
    let full = Scissor::full(&f.plan.camera);
    let zfail = f
        .parts
        .iter()
        .find(|p| p.counting == Counting::ZFail)
        .unwrap();
    assert_eq!(zfail.scissor, Some(full));
}

// ---------------------------------------------------------------------------------------------
// Fits

/// Box A (depth-pass) and an alpha-tested box (depth-fail) beside it, seen from far off.
fn fit_scene() -> Scene {
    let mut scene = between_scene();
    add(
        &mut scene,
        &cuboid(
            Vec3::new(30.0, -10.0, 20.0),
            Vec3::new(50.0, 10.0, 40.0),
            8.0,
        ),
        alpha_caster_material(),
        SurfaceOwner::World,
    );
    scene
}

/// The constant clip plane of a flat depth buffer: window depth ≤ d (plus the rounding margin
/// of 2^-16), i.e. (0, 0, -1, 2d - 1) in clip space; the other planes zero.
fn assert_flat_clip(planes: [[f32; 4]; 4], d: f32) {
    let w = 2.0 * (d + 1.0 / 65536.0) - 1.0;
    let [p, rest @ ..] = planes;
    assert!(
        p[0].abs() < 1e-5 && p[1].abs() < 1e-5 && p[2] == -1.0 && (p[3] - w).abs() < 1e-5,
        "{planes:?}: expected (0, 0, -1, {w})"
    );
    assert!(rest.iter().all(|q| *q == [0.0; 4]), "{planes:?}");
}

/// Guards `plan.depth_clip`: once the planner has asked for the depth and been handed a flat one
/// (0.9 everywhere), the depth-pass part is clipped at that depth and the depth-fail part is
/// not. Without `plan.depth_clip` the depth is not asked for and nothing is clipped.
#[test]
fn depth_pass_parts_are_clipped_behind_the_depth() {
    let scene = fit_scene();
    // The clip-plane emulation: where EXT_depth_bounds_test is chosen it replaces the planes.
    let o = options(&["plan.depth_clip=true", "plan.depth_bounds_test=false"]);
    let f = frame(
        &mut Planner::default(),
        &scene,
        &far_camera(),
        &o,
        Some(0.9),
    );
    assert_eq!(f.need, DepthNeed::Read { reduced: false });
    assert_eq!(f.parts.len(), 2);
    for p in &f.parts {
        match p.counting {
            Counting::ZPass => assert_flat_clip(p.depth_clip, 0.9),
            Counting::ZFail => assert_eq!(p.depth_clip, NO_CLIP),
        }
    }
    assert_eq!(f.stats.parts_depth_clipped, 1);

    let f = frame(
        &mut Planner::default(),
        &scene,
        &far_camera(),
        &options(&[]),
        Some(0.9),
    );
    assert_eq!(f.need, DepthNeed::None);
    assert!(f.parts.iter().all(|p| p.depth_clip == NO_CLIP));
    assert_eq!(f.stats.parts_depth_clipped, 0);
}

/// Guards the fits' key (`plan.reuse_depth_fits`): a second frame handed the same depth takes
/// the depth-pass part's fit from the first; one handed another depth (0.8) fits again, to
/// that depth; and the same depth once more, kept as the planner's last (`DepthNeed::Reuse`),
/// reuses that fit. Draws are not kept (`plan.reuse_volume_draws` off), so each frame lays its
/// parts out.
#[test]
fn depth_fits_are_reused_only_for_the_same_depth() {
    let scene = fit_scene();
    let o = options(&[
        "plan.depth_clip=true",
        "plan.depth_bounds_test=false",
        "plan.reuse_volume_draws=false",
        "plan.reuse_depth=false",
    ]);
    let camera = far_camera();
    let mut planner = Planner::default();
    let zpass = |f: &Frame| {
        let p: Vec<_> = f
            .parts
            .iter()
            .filter(|p| p.counting == Counting::ZPass)
            .collect();
        assert_eq!(p.len(), 1);
        p[0].depth_clip
    };
    let first = frame(&mut planner, &scene, &camera, &o, Some(0.9));
    assert_eq!(first.stats.depth_fits_reused, 0);
    assert_flat_clip(zpass(&first), 0.9);

    let same = frame(&mut planner, &scene, &camera, &o, Some(0.9));
    assert_eq!(same.need, DepthNeed::Read { reduced: false });
    assert_eq!(same.stats.depth_fits_reused, 1);
    assert_eq!(zpass(&same), zpass(&first));

    let changed = frame(&mut planner, &scene, &camera, &o, Some(0.8));
    assert_eq!(changed.stats.depth_fits_reused, 0);
    assert_flat_clip(zpass(&changed), 0.8);

    // The depth kept from the last frame (`plan.reuse_depth`): not read, its fits kept.
    let o = options(&[
        "plan.depth_clip=true",
        "plan.depth_bounds_test=false",
        "plan.reuse_volume_draws=false",
    ]);
    let kept = frame(&mut planner, &scene, &camera, &o, None);
    assert_eq!(kept.need, DepthNeed::Reuse);
    assert_eq!(kept.stats.depth_fits_reused, 1);
    assert_flat_clip(zpass(&kept), 0.8);

    // Without `reuse_depth_fits` the same depth is fitted again.
    let o = options(&[
        "plan.depth_clip=true",
        "plan.depth_bounds_test=false",
        "plan.reuse_volume_draws=false",
        "plan.reuse_depth=false",
        "plan.reuse_depth_fits=false",
    ]);
    let mut planner = Planner::default();
    frame(&mut planner, &scene, &camera, &o, Some(0.9));
    let again = frame(&mut planner, &scene, &camera, &o, Some(0.9));
    assert_eq!(again.stats.depth_fits_reused, 0);
}

// ---------------------------------------------------------------------------------------------
// Reuse keys

/// Box A in the world and a model box (model space -5..5, -5..5, 0..10) placed at (30, 0, 20).
fn model_scene() -> Scene {
    let mut scene = between_scene();
    scene.models.push(ModelInstance::new(
        "model",
        Mat4::from_translation(Vec3::new(30.0, 0.0, 20.0)),
    ));
    add(
        &mut scene,
        &cuboid(Vec3::new(-5.0, -5.0, 0.0), Vec3::new(5.0, 5.0, 10.0), 8.0),
        caster_material(),
        SurfaceOwner::Model(0),
    );
    scene
}

/// Guards the volume draws' key (`plan.reuse_volume_draws`): the same frame again draws what
/// was drawn (nothing built, nothing uploaded); moving the model rebuilds its part alone (the
/// world box's part is reused: its key holds no other caster's transform); moving the light
/// rebuilds both. Without the switch nothing is kept whole.
#[test]
fn volume_draws_are_reused_until_a_light_or_a_model_moves() {
    let mut scene = model_scene();
    let camera = far_camera();
    let o = options(&[]);
    let mut planner = Planner::default();

    let first = frame(&mut planner, &scene, &camera, &o, None);
    assert_eq!(light0(&first.plan).volumes.len(), 2);
    assert!(!first.stats.draws_reused);
    assert_eq!((first.stats.parts_built, first.stats.parts_reused), (2, 0));
    assert!(first.uploads_vertices);

    let again = frame(&mut planner, &scene, &camera, &o, None);
    assert!(again.stats.draws_reused);
    assert_eq!(again.stats.parts_built, 0);
    assert!(!again.uploads_vertices);
    assert_eq!(again.draws.len(), first.draws.len());

    let moved = Mat4::from_translation(Vec3::new(30.0, 10.0, 20.0));
    shadowlab::viewer::edit::move_model(&mut scene, 0, moved);
    let model_moved = frame(&mut planner, &scene, &camera, &o, None);
    assert!(!model_moved.stats.draws_reused);
    assert_eq!(
        (
            model_moved.stats.parts_built,
            model_moved.stats.parts_reused
        ),
        (1, 1)
    );
    assert!(model_moved.uploads_vertices);

    scene.lights[0].position += Vec3::new(5.0, 0.0, 0.0);
    let light_moved = frame(&mut planner, &scene, &camera, &o, None);
    assert!(!light_moved.stats.draws_reused);
    assert_eq!(light_moved.stats.parts_built, 2);
    assert!(light_moved.uploads_vertices);

    // Nothing kept whole without the switch (parts still come from the part cache).
    let o = options(&["plan.reuse_volume_draws=false"]);
    let mut planner = Planner::default();
    frame(&mut planner, &scene, &camera, &o, None);
    let again = frame(&mut planner, &scene, &camera, &o, None);
    assert!(!again.stats.draws_reused);
    assert_eq!((again.stats.parts_built, again.stats.parts_reused), (0, 2));
}

/// Guards `shadow_volume.relayout_on_gpu`: once a light's upload is made, the planner gives up
/// its CPU copies of the parts (nothing reads them without `plan.cull_clipped`), and a later
/// layout names a part it still draws by its place in the old buffer (copied on the GPU),
/// writing only the part built again. With the clip test, or with the switch off, the copies
/// stay (within `shadow_volume.kept_mb`). Made to fail: with no copy given up, both parts were
/// written again from the CPU.
#[test]
fn a_part_given_up_on_the_cpu_is_laid_out_again_from_the_gpu() {
    let held_after_moving = |sets: &[&str]| {
        let mut scene = model_scene();
        let camera = far_camera();
        let o = options(sets);
        let mut planner = Planner::default();
        frame(&mut planner, &scene, &camera, &o, None);
        planner.uploaded(0);
        let moved = Mat4::from_translation(Vec3::new(30.0, 10.0, 20.0));
        shadowlab::viewer::edit::move_model(&mut scene, 0, moved);
        let model_moved = frame(&mut planner, &scene, &camera, &o, None);
        assert_eq!(
            (
                model_moved.stats.parts_built,
                model_moved.stats.parts_reused
            ),
            (1, 1)
        );
        let lv = planner.last_volume_draws(0).expect("prepared");
        let spans = lv.upload.spans.clone().expect("an upload");
        planner.uploaded(0);
        (spans, planner.held_volumes().2)
    };
    let written = |spans: &[Span]| {
        spans
            .iter()
            .filter(|s| matches!(s, Span::Written(_)))
            .count()
    };
    let (spans, bytes) = held_after_moving(&["plan.cull_clipped=false"]);
    // The model's part built again and written; the world box's taken from the buffer.
    assert_eq!(spans.len(), 2, "{spans:?}");
    assert_eq!(written(&spans), 1, "{spans:?}");
    // Given up this frame: only the part just built is still on the CPU, until the next
    // prepare.
    let (_, one_part) = held_after_moving(&[
        "plan.cull_clipped=false",
        "shadow_volume.relayout_on_gpu=false",
    ]);
    assert!(
        bytes < one_part,
        "{bytes} bytes held, {one_part} with the copies kept"
    );
    for kept in [
        &["plan.cull_clipped=true"][..],
        &[
            "plan.cull_clipped=false",
            "shadow_volume.relayout_on_gpu=false",
        ],
    ] {
        let (spans, _) = held_after_moving(kept);
        assert_eq!(written(&spans), spans.len(), "{kept:?}: {spans:?}");
    }
}

/// Guards the caster groups' key (the scene's revision): the same groups while the scene's
/// surfaces stay, new ones (with the new caster) after `push_surface`; moving a model keeps
/// them (its groups are in model space).
#[test]
fn caster_groups_are_kept_until_a_surface_is_added() {
    let mut scene = model_scene();
    let mut planner = Planner::default();
    let a = planner.casters(&scene);
    let b = planner.casters(&scene);
    assert!(Arc::ptr_eq(&a, &b));
    assert_eq!(a.groups[0].components.len(), 1);

    shadowlab::viewer::edit::move_model(
        &mut scene,
        0,
        Mat4::from_translation(Vec3::new(0.0, 30.0, 20.0)),
    );
    assert!(Arc::ptr_eq(&a, &planner.casters(&scene)));

    add_box(
        &mut scene,
        Vec3::new(-50.0, -10.0, 20.0),
        Vec3::new(-30.0, 10.0, 40.0),
    );
    let c = planner.casters(&scene);
    assert!(!Arc::ptr_eq(&a, &c));
    assert_eq!(c.groups[0].components.len(), 2);
    assert!(Arc::ptr_eq(&c, &planner.casters(&scene)));
}

/// Guards the depth's key (`plan.reuse_depth`): after a read, the same camera, surfaces and
/// models make `Reuse`; a moved camera or a moved model make `Read` again; without the switch
/// every frame reads.
#[test]
fn the_depth_is_reused_while_camera_and_models_stay() {
    let mut scene = model_scene();
    let o = options(&["plan.occlusion=true"]);
    let camera = far_camera();
    let mut planner = Planner::default();
    let need = |planner: &mut Planner, scene: &Scene, camera: &Camera, o: &Options| {
        frame(planner, scene, camera, o, Some(0.999)).need
    };
    let read = DepthNeed::Read { reduced: false };
    assert_eq!(need(&mut planner, &scene, &camera, &o), read);
    assert_eq!(need(&mut planner, &scene, &camera, &o), DepthNeed::Reuse);
    assert_eq!(need(&mut planner, &scene, &camera, &o), DepthNeed::Reuse);

    let moved = Camera::looking_at(Vec3::new(600.0, 50.0, 300.0), Vec3::ZERO);
    assert_eq!(need(&mut planner, &scene, &moved, &o), read);
    assert_eq!(need(&mut planner, &scene, &moved, &o), DepthNeed::Reuse);

    shadowlab::viewer::edit::move_model(
        &mut scene,
        0,
        Mat4::from_translation(Vec3::new(30.0, 10.0, 20.0)),
    );
    assert_eq!(need(&mut planner, &scene, &moved, &o), read);
    assert_eq!(need(&mut planner, &scene, &moved, &o), DepthNeed::Reuse);

    let o = options(&["plan.occlusion=true", "plan.reuse_depth=false"]);
    assert_eq!(need(&mut planner, &scene, &moved, &o), read);
    assert_eq!(need(&mut planner, &scene, &moved, &o), read);

    // Neither occlusion nor the depth clip: nothing to read.
    assert_eq!(
        need(&mut planner, &scene, &moved, &options(&[])),
        DepthNeed::None
    );
}
