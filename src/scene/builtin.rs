//! The built-in default scene: a room whose casters each exercise one shadow problem.
//!
//! - box: hard straight shadow edges and a contact shadow on the floor;
//! - sphere (floating): a curved silhouette and a shadow detached from its caster;
//! - torus (tilted): self-shadowing;
//! - thin pole: a caster thinner than a shadow-map texel at low map sizes;
//! - grate (alpha-tested, two-sided): a patterned shadow that only alpha-aware casters get right;
//! - one spot light (the paper's shadow-map light) and one omni light.
//!
//! It needs no files, so `render`, `view`, the tests and CI always have a scene.

use super::shapes::{MeshData, cuboid, cylinder, sphere, torus};
use super::{AlphaFunc, Camera, Cull, Light, Material, Scene, SurfaceKind, SurfaceOwner};
use crate::images::Rgba;
use glam::Vec3;

/// Half the side of the square room, in Quake units.
pub const ROOM_HALF: f32 = 256.0;
/// Height of the room's walls.
pub const ROOM_HEIGHT: f32 = 192.0;
/// Where the spot light stands and what it aims at.
pub const SPOT_POSITION: Vec3 = Vec3::new(-60.0, -170.0, 230.0);
pub const SPOT_TARGET: Vec3 = Vec3::new(10.0, 20.0, 0.0);
pub const SPOT_CUTOFF_DEG: f32 = 38.0;
pub const OMNI_POSITION: Vec3 = Vec3::new(170.0, -140.0, 130.0);
/// Height of the horizontal grate.
pub const GRATE_Z: f32 = 92.0;

fn checker(size: u32, cell: u32, a: [u8; 3], b: [u8; 3]) -> Rgba {
    let mut rgba = Vec::with_capacity((size * size * 4) as usize);
    for y in 0..size {
        for x in 0..size {
            let c = if ((x / cell) + (y / cell)).is_multiple_of(2) {
                a
            } else {
                b
            };
            rgba.extend_from_slice(&[c[0], c[1], c[2], 255]);
        }
    }
    Rgba {
        width: size,
        height: size,
        data: rgba,
    }
}

fn bricks(size: u32) -> Rgba {
    let mut rgba = Vec::with_capacity((size * size * 4) as usize);
    for y in 0..size {
        for x in 0..size {
            let row = y / 16;
            let shift = if row.is_multiple_of(2) { 0 } else { 16 };
            let mortar = y % 16 == 0 || (x + shift) % 32 == 0;
            let c = if mortar {
                [120, 115, 105]
            } else {
                [178, 150, 122]
            };
            rgba.extend_from_slice(&[c[0], c[1], c[2], 255]);
        }
    }
    Rgba {
        width: size,
        height: size,
        data: rgba,
    }
}

/// Metal bars with square holes: alpha 255 on bars, 0 in holes.
pub fn grate_image(size: u32, cells: u32, bar: u32) -> Rgba {
    let cell = size / cells;
    let mut rgba = Vec::with_capacity((size * size * 4) as usize);
    for y in 0..size {
        for x in 0..size {
            let on_bar = x % cell < bar || y % cell < bar;
            rgba.extend_from_slice(&[170, 172, 180, if on_bar { 255 } else { 0 }]);
        }
    }
    Rgba {
        width: size,
        height: size,
        data: rgba,
    }
}

/// Builds the built-in scene.
pub fn default_scene() -> Scene {
    let mut scene = Scene {
        name: "builtin".to_string(),
        ..Scene::default()
    };
    let add_material = |scene: &mut Scene, name: &str, image: Rgba| -> usize {
        scene.textures.push(image);
        scene
            .materials
            .push(Material::opaque(name, Some(scene.textures.len() - 1)));
        scene.materials.len() - 1
    };
    let floor_mat = add_material(
        &mut scene,
        "floor",
        checker(64, 32, [150, 150, 150], [112, 112, 118]),
    );
    let wall_mat = add_material(&mut scene, "wall", bricks(64));
    let box_mat = add_material(
        &mut scene,
        "box",
        checker(16, 8, [214, 140, 60], [190, 120, 50]),
    );
    let sphere_mat = add_material(&mut scene, "sphere", Rgba::solid([120, 170, 230, 255]));
    let torus_mat = add_material(
        &mut scene,
        "torus",
        checker(16, 4, [110, 200, 110], [80, 160, 80]),
    );
    let pole_mat = add_material(&mut scene, "pole", Rgba::solid([230, 230, 230, 255]));
    let grate_mat = add_material(&mut scene, "grate", grate_image(64, 4, 4));
    scene.materials[grate_mat].alpha_test = Some(AlphaFunc::Ge128);
    scene.materials[grate_mat].cull = Cull::None;

    let world = |scene: &mut Scene, m: MeshData, mat: usize| {
        scene.push_surface(
            &m.vertices,
            &m.indices,
            mat,
            SurfaceOwner::World,
            SurfaceKind::Mesh,
        );
    };

    // Room: floor and four walls, facing inward.
    let (h, t) = (ROOM_HALF, ROOM_HEIGHT);
    let mut floor = MeshData::default();
    floor.quad(
        Vec3::new(-h, -h, 0.0),
        Vec3::new(h, -h, 0.0),
        Vec3::new(h, h, 0.0),
        Vec3::new(-h, h, 0.0),
        [2.0 * h / 64.0, 2.0 * h / 64.0],
    );
    world(&mut scene, floor, floor_mat);
    let mut walls = MeshData::default();
    let uv = [2.0 * h / 64.0, t / 64.0];
    let c = |x: f32, y: f32, z: f32| Vec3::new(x, y, z);
    walls.quad(c(-h, -h, 0.0), c(-h, h, 0.0), c(-h, h, t), c(-h, -h, t), uv); // x = -h, faces +X
    walls.quad(c(h, h, 0.0), c(h, -h, 0.0), c(h, -h, t), c(h, h, t), uv); // x = +h, faces -X
    walls.quad(c(h, -h, 0.0), c(-h, -h, 0.0), c(-h, -h, t), c(h, -h, t), uv); // y = -h, faces +Y
    walls.quad(c(-h, h, 0.0), c(h, h, 0.0), c(h, h, t), c(-h, h, t), uv); // y = +h, faces -Y
    world(&mut scene, walls, wall_mat);

    world(
        &mut scene,
        cuboid(
            Vec3::new(-130.0, -40.0, 0.0),
            Vec3::new(-66.0, 24.0, 64.0),
            32.0,
        ),
        box_mat,
    );
    world(
        &mut scene,
        sphere(Vec3::new(50.0, -50.0, 64.0), 34.0, 32, 16),
        sphere_mat,
    );
    world(
        &mut scene,
        torus(Vec3::new(120.0, 100.0, 58.0), 40.0, 12.0, 40, 16, 60.0),
        torus_mat,
    );
    world(
        &mut scene,
        cylinder(Vec3::new(-40.0, 130.0, 0.0), 3.0, 150.0, 12),
        pole_mat,
    );

    // Grate: a horizontal quad, drawn from both sides.
    let mut grate = MeshData::default();
    let (gx, gy, gs) = (-20.0, 30.0, 96.0);
    grate.quad(
        c(gx, gy, GRATE_Z),
        c(gx + gs, gy, GRATE_Z),
        c(gx + gs, gy + gs, GRATE_Z),
        c(gx, gy + gs, GRATE_Z),
        [1.0, 1.0],
    );
    world(&mut scene, grate, grate_mat);

    scene.lights.push(Light {
        color: Vec3::new(1.0, 0.93, 0.8),
        ..Light::spot("spot", SPOT_POSITION, SPOT_TARGET, SPOT_CUTOFF_DEG, 700.0)
    });
    scene.lights.push(Light {
        color: Vec3::new(0.55, 0.65, 0.9),
        ..Light::omni("omni", OMNI_POSITION, 520.0)
    });
    scene.camera = Camera::looking_at(
        Vec3::new(-235.0, -235.0, 185.0),
        Vec3::new(20.0, 30.0, 20.0),
    );
    scene
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_scene_has_the_documented_parts() {
        let s = default_scene();
        assert_eq!(s.lights.len(), 2);
        assert!(s.lights[0].is_spot() && !s.lights[1].is_spot());
        let names: Vec<_> = s.materials.iter().map(|m| m.name.as_str()).collect();
        for n in ["floor", "wall", "box", "sphere", "torus", "pole", "grate"] {
            assert!(names.contains(&n), "{n}");
        }
        let b = s.bounds();
        assert_eq!(b.min, Vec3::new(-ROOM_HALF, -ROOM_HALF, 0.0));
        assert_eq!(b.max, Vec3::new(ROOM_HALF, ROOM_HALF, ROOM_HEIGHT));
        for i in &s.indices {
            assert!((*i as usize) < s.vertices.len());
        }
    }

    #[test]
    fn grate_texture_has_holes() {
        let g = grate_image(64, 4, 4);
        let opaque = g.data.chunks_exact(4).filter(|p| p[3] == 255).count();
        // Each 16x16 cell has a 4-texel bar on two sides: 16*16 - 12*12 = 112 of 256.
        assert_eq!(opaque, 112 * 16);
    }
}
