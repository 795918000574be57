//! What shadow maps hold in memory, and whether a frame's maps fit `shadow_map.budget_mb`:
//! the planner decides from it whether every light's maps are drawn first (they fit) or each
//! light's just before its own pass (they do not); the GL layer counts its textures with the
//! same sizes, so the two agree on what "fits" means.

use super::{LightPlan, Plan};
use crate::options::{DepthBits, MapBuffer, ShadowMapOptions};
use crate::shadow::views::ViewKind;

/// Bytes of one depth texel of `bits` as drivers store it (24-bit depth in 32-bit words).
fn depth_texel_bytes(bits: DepthBits) -> u64 {
    match bits {
        DepthBits::D16 => 2,
        DepthBits::D24 | DepthBits::D32f => 4,
    }
}

/// Bytes of a depth texture: `size`² (six faces for a cube) at `levels` mip levels.
pub fn depth_texture_bytes(cube: bool, size: u32, bits: DepthBits, levels: u32) -> u64 {
    let faces = if cube { 6 } else { 1 };
    let texels: u64 = (0..levels.max(1))
        .map(|l| u64::from((size >> l).max(1)).pow(2))
        .sum();
    faces * texels * depth_texel_bytes(bits)
}

/// Bytes of an ID buffer's colour texture of side `size` (RGBA8).
pub fn id_texture_bytes(size: u32) -> u64 {
    u64::from(size).pow(2) * 4
}

/// Mip levels of a view's texture of side `size`: a priority buffer's chain down to one texel
/// (`shadow_map.priority_mipmap`; never a cube: priority maps are six spots), else one.
pub fn view_levels(buffer: MapBuffer, priority_mipmap: bool, cube: bool, size: u32) -> u32 {
    if buffer == MapBuffer::Priority && priority_mipmap && !cube {
        32 - size.max(1).leading_zeros()
    } else {
        1
    }
}

/// Bytes of light `lp`'s maps: each view's texture, its static map where it has one, and
/// its ID buffer's colour where it stores IDs.
pub fn light_map_bytes(lp: &LightPlan, o: &ShadowMapOptions) -> u64 {
    if !lp.technique.uses_maps() {
        return 0;
    }
    lp.views
        .iter()
        .enumerate()
        .map(|(vi, view)| {
            let cube = view.kind == ViewKind::Cube;
            let size = view.map_size();
            let levels = view_levels(lp.buffer, o.priority_mipmap, cube, size);
            let map = depth_texture_bytes(cube, size, o.depth_bits, levels);
            let statics = lp
                .view_static_keys
                .get(vi)
                .copied()
                .flatten()
                .map_or(0, |_| map);
            let ids = if lp.buffer == MapBuffer::Id {
                id_texture_bytes(size)
            } else {
                0
            };
            map + statics + ids
        })
        .sum()
}

/// The budget in bytes, or `None` for no limit (`budget_mb = 0`).
pub fn budget_bytes(o: &ShadowMapOptions) -> Option<u64> {
    (o.budget_mb > 0.0).then(|| (f64::from(o.budget_mb) * 1048576.0) as u64)
}

/// Whether the frame draws each light's maps just before its own pass: its maps together
/// hold more than the budget, or (with a budget set) they would be held beside its lights'
/// volume buffers on the paper's frame (`drawn_each_frame`: nothing keeps its maps for a later
/// frame, so drawing each light's before its pass costs no draw more). A paper's-frame hybrid
/// on oa_dm3 held 384 MB of maps beside 645 MB of volume buffers. Bytes of the frame's maps
/// together beside it.
pub fn maps_per_light(plan: &Plan, o: &ShadowMapOptions, drawn_each_frame: bool) -> (bool, u64) {
    let bytes: u64 = plan.lights.iter().map(|lp| light_map_bytes(lp, o)).sum();
    let beside_volumes = drawn_each_frame && bytes > 0 && plan.any_volumes();
    (
        budget_bytes(o).is_some_and(|b| bytes > b || beside_volumes),
        bytes,
    )
}

/// Bytes the frame's map textures may hold together: the budget, or, where each light's maps
/// are drawn just before its pass and no view's map is kept for a later frame (no view has a
/// key: the paper's frame, or `plan.cache_maps = false`), only what the largest light needs.
/// A texture of a light already drawn then holds nothing anything reads again, so the next
/// light takes it over; kept to the budget, they had filled it with maps never read (a
/// paper's-frame hybrid on oa_dm3 under `omni = frusta`: 542 MB in 672 textures).
pub fn held_bytes(plan: &Plan, o: &ShadowMapOptions) -> Option<u64> {
    let budget = budget_bytes(o);
    let kept = plan.lights.iter().any(|lp| {
        lp.view_keys.iter().any(Option::is_some) || lp.view_static_keys.iter().any(Option::is_some)
    });
    if !plan.maps_per_light || kept {
        return budget;
    }
    let largest = plan.lights.iter().map(|lp| light_map_bytes(lp, o)).max();
    match (budget, largest) {
        (Some(b), Some(l)) => Some(b.min(l)),
        (b, _) => b,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn texture_sizes() {
        // A 2048-texel cube of 24-bit depth: 6 × 2048² × 4 bytes, about 100 MB.
        assert_eq!(
            depth_texture_bytes(true, 2048, DepthBits::D24, 1),
            6 * 2048 * 2048 * 4
        );
        assert_eq!(
            depth_texture_bytes(false, 512, DepthBits::D16, 1),
            512 * 512 * 2
        );
        // A full chain of a 4-texel map: 16 + 4 + 1 texels.
        assert_eq!(view_levels(MapBuffer::Priority, true, false, 4), 3);
        assert_eq!(view_levels(MapBuffer::Priority, true, true, 4), 1);
        assert_eq!(view_levels(MapBuffer::Depth, true, false, 4), 1);
        assert_eq!(depth_texture_bytes(false, 4, DepthBits::D32f, 3), 21 * 4);
        assert_eq!(id_texture_bytes(256), 256 * 256 * 4);
    }

    #[test]
    fn no_budget_at_zero() {
        let mut o = ShadowMapOptions {
            budget_mb: 0.0,
            ..ShadowMapOptions::default()
        };
        assert_eq!(budget_bytes(&o), None);
        o.budget_mb = 1.5;
        assert_eq!(budget_bytes(&o), Some(1572864));
    }
}
