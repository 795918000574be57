//! What each fuzz target does with its input, one function per loader. The targets in `fuzz/`
//! and the regression replay in `tests/fuzz_regressions.rs` both call these, so a crash input
//! replays through exactly the calls that found it. Every function must return (never panic,
//! never allocate without bound) whatever the bytes are.

use crate::options::Options;
use crate::q3::{bsp, entities, md3, patch, pk3, rtlights, shader};
use crate::scene::Camera;
use crate::scene::path;
use crate::scene_file::SceneFile;
use crate::viewer::script;
use glam::{Mat4, Vec3};
use std::path::Path;

/// A target's name and its function, for the replay test and `scripts/fuzz.sh`'s listing.
pub type Target = (&'static str, fn(&[u8]));

/// Every target, named as its folder under `fuzz/corpus/` and `tests/fuzz-inputs/`.
pub const TARGETS: &[Target] = &[
    ("pk3", pk3),
    ("bsp", bsp),
    ("patch", patch),
    ("shader", shader),
    ("md3", md3),
    ("skin", skin),
    ("animation_cfg", animation_cfg),
    ("entities", entities),
    ("rtlights", rtlights),
    ("scene_file", scene_file),
    ("camera_path", camera_path),
    ("viewer_script", viewer_script),
];

/// Names that try to climb out of the archive or hide behind separators and case.
const PATH_TRICKS: &[&str] = &[
    "../../../../etc/passwd",
    "..\\..\\boot.ini",
    "/maps/../maps/x.bsp",
    "\\\\server\\share\\x",
    "MAPS\\X.BSP",
    " ./scripts/./a.shader ",
    "",
    "/",
];

/// A pk3 held in memory: the central directory (entry counts, names), every name's lookup and
/// origin, and reading each entry under the VFS's size, ratio and declared-size checks.
pub fn pk3(data: &[u8]) {
    let mut vfs = pk3::Vfs::new();
    if vfs
        .add_pk3_bytes(Path::new("fuzz.pk3"), data.to_vec())
        .is_err()
    {
        return;
    }
    for name in vfs.list("", "") {
        assert!(vfs.contains(&name), "listed but not found: {name:?}");
        let _ = vfs.origin(&name);
        let _ = vfs.read(&name);
        let _ = vfs.read(&format!("../{name}"));
    }
    for trick in PATH_TRICKS {
        let _ = vfs.read(trick);
        let _ = vfs.list(trick, "");
    }
}

/// IBSP parsing, then what indexes with the values the parser validated: patch tessellation
/// (at Quake 3's usual level) and walks of the node tree.
pub fn bsp(data: &[u8]) {
    let Ok(map) = bsp::parse(data) else { return };
    for s in &map.surfaces {
        if s.kind == bsp::SurfaceType::Patch {
            let first = s.first_vert as usize;
            let control = &map.vertices[first..first + s.num_verts as usize];
            let _ = patch::tessellate(control, s.patch_width as usize, s.patch_height as usize, 4);
        }
    }
    for v in map.vertices.iter().take(16) {
        let _ = map.leaf_at(v.position);
    }
}

/// Bytes of a control vertex: position, st, lightmap st, normal (10 f32) and a colour.
const VERT_BYTES: usize = 44;

/// Patch tessellation of any grid: the first three bytes are width, height and level; the rest
/// are control vertices, repeated to fill the grid (so that small inputs reach big grids) unless
/// the level byte's high bit asks for them as given (to reach the count check).
pub fn patch(data: &[u8]) {
    let [w, h, level, rest @ ..] = data else {
        return;
    };
    let given: Vec<bsp::DrawVert> = rest.chunks_exact(VERT_BYTES).map(draw_vert).collect();
    let (width, height) = (*w as usize, *h as usize);
    let control = if level & 0x80 != 0 || given.is_empty() {
        given
    } else {
        given.iter().copied().cycle().take(width * height).collect()
    };
    let _ = patch::tessellate(&control, width, height, u32::from(level & 0x7f));
}

fn draw_vert(b: &[u8]) -> bsp::DrawVert {
    let f = |i: usize| f32::from_le_bytes([b[4 * i], b[4 * i + 1], b[4 * i + 2], b[4 * i + 3]]);
    bsp::DrawVert {
        position: [f(0), f(1), f(2)],
        st: [f(3), f(4)],
        lightmap: [f(5), f(6)],
        normal: [f(7), f(8), f(9)],
        color: [b[40], b[41], b[42], b[43]],
    }
}

/// Shader scripts, parsed alone and through the library (which merges and looks up names).
pub fn shader(data: &[u8]) {
    let text = String::from_utf8_lossy(data);
    let (defs, _) = shader::parse_shader_script(&text);
    for d in &defs {
        let _ = d.to_material(None);
        let _ = (d.casts_shadows(), d.visible(), d.receives_light());
        let _ = shader::image_candidates(&d.name);
    }
    let mut library = shader::ShaderLibrary::new();
    library.add_script(&text, "fuzz.shader");
    for d in &defs {
        let _ = library.get(&d.name);
    }
}

/// MD3 parsing, then placing frame 0 and assembling a player from three copies.
pub fn md3(data: &[u8]) {
    let Ok(m) = md3::parse(data) else { return };
    let _ = md3::place_model(&m, 0, Mat4::IDENTITY);
    let _ = md3::assemble_player(&m, &m, &m, 0, 0);
    for frame in 0..m.num_frames().min(4) {
        let _ = m.tag(frame, "tag_torso");
    }
}

/// `.skin` files and their lookups.
pub fn skin(data: &[u8]) {
    let text = String::from_utf8_lossy(data);
    let skin = md3::parse_skin(&text);
    for (name, _) in &skin.entries {
        let _ = skin.shader_for(&name.to_ascii_uppercase());
    }
}

/// `animation.cfg`, then every animation and the frames a player is posed in.
pub fn animation_cfg(data: &[u8]) {
    let text = String::from_utf8_lossy(data);
    let Ok(cfg) = md3::parse_animation_cfg(&text) else {
        return;
    };
    for id in md3::AnimationId::ALL {
        let _ = cfg.get(id);
    }
    let _ = (
        cfg.animations().len(),
        cfg.legs_offset(),
        cfg.torso_stand_frame(),
        cfg.legs_idle_frame(),
    );
}

/// Entity lumps, then spawn points and both ways of turning entities into lights.
pub fn entities(data: &[u8]) {
    let text = String::from_utf8_lossy(data);
    let Ok(ents) = entities::parse_entities(&text) else {
        return;
    };
    for e in &ents {
        let _ = (e.classname(), e.origin(), e.angle());
    }
    let _ = entities::spawn_points(&ents);
    let _ = entities::light_entities(&ents);
    let _ = entities::placed_lights(&ents);
}

/// DarkPlaces `.rtlights` files and the lights made of them.
pub fn rtlights(data: &[u8]) {
    let text = String::from_utf8_lossy(data);
    let Ok(lights) = rtlights::parse_rtlights(&text) else {
        return;
    };
    for (i, l) in lights.iter().enumerate() {
        let _ = l.to_light(&format!("rt{i}"));
    }
}

/// Scene files (TOML); one without a map is built, which touches no files (a map would read
/// the data set from disk, so those stop after parsing).
pub fn scene_file(data: &[u8]) {
    let text = String::from_utf8_lossy(data);
    let Ok(file) = SceneFile::parse(&text, Path::new("fuzz.toml")) else {
        return;
    };
    if file.map.is_none() && file.lights.rtlights.is_none() {
        let _ = file.build(&Options::default());
    }
}

/// Recorded camera paths; a parsed path must print back to the same keys.
pub fn camera_path(data: &[u8]) {
    let text = String::from_utf8_lossy(data);
    let Ok(keys) = path::parse(&text, "fuzz.path") else {
        return;
    };
    let base = Camera::looking_at(Vec3::ZERO, Vec3::X);
    for k in keys.iter().take(16) {
        let c: Camera = k.apply(&base);
        let _ = c.view();
    }
    let again = path::parse(&path::to_text(&keys), "again").expect("a printed path parses");
    assert_eq!(again.len(), keys.len());
}

/// Viewer scripts (`shadowlab view --script`).
pub fn viewer_script(data: &[u8]) {
    let text = String::from_utf8_lossy(data);
    let _ = script::parse(&text);
}
