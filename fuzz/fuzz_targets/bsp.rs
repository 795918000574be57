//! IBSP parsing, then everything that indexes with what the parser validated: patch
//! tessellation and walks of the node tree.
#![no_main]
use libfuzzer_sys::fuzz_target;
use shadowlab::q3::{bsp, patch};

fuzz_target!(|data: &[u8]| {
    let Ok(map) = bsp::parse(data) else { return };
    for s in &map.surfaces {
        if s.kind == bsp::SurfaceType::Patch {
            let control = &map.vertices[s.first_vert as usize..(s.first_vert + s.num_verts) as usize];
            let _ = patch::tessellate(control, s.patch_width as usize, s.patch_height as usize, 2);
        }
    }
    for v in map.vertices.iter().take(16) {
        let _ = map.leaf_at(v.position);
    }
});
