//! Frusta of static omni lights kept across frames (`plan.keep_frusta`; Forsyth: frusta
//! "persistent with random re-checks" for static lights, dynamic for moving ones). A light
//! keeps the frusta chosen for it while it stands where it stood and every receiver in view
//! stays within them (`shadow::frusta::still_cover`), so its views and maps stay the same and
//! the map cache reuses them; one frame in [`RECHECK_EVERY`], at a phase of its own, it chooses
//! again whatever it finds.

use crate::shadow::frusta::FaceFrustum;
use std::collections::HashMap;

/// A light's frusta are chosen again at least this often, in frames.
pub const RECHECK_EVERY: u64 = 16;

/// Frusta as chosen per light, with what they were chosen for.
#[derive(Debug, Clone, Default)]
pub struct KeptFrusta {
    lights: HashMap<usize, (u64, Vec<FaceFrustum>)>,
    /// Frames recorded.
    frame: u64,
}

impl KeptFrusta {
    /// The frusta light `light` may keep: those chosen for `key` (its position, radius and map
    /// options), unless this is the light's frame to choose again.
    pub fn get(&self, light: usize, key: u64) -> Option<&[FaceFrustum]> {
        // A phase per light from a multiplicative hash: lights do not all choose at once.
        let phase = (light as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 60;
        if (self.frame + phase).is_multiple_of(RECHECK_EVERY) {
            return None;
        }
        match self.lights.get(&light) {
            Some((k, frusta)) if *k == key => Some(frusta),
            _ => None,
        }
    }

    /// Takes the frame's frusta (light, key, frusta) for the next frame; lights without frusta
    /// this frame are forgotten.
    pub fn record(&mut self, chosen: impl IntoIterator<Item = (usize, u64, Vec<FaceFrustum>)>) {
        self.lights = chosen
            .into_iter()
            .map(|(light, key, frusta)| (light, (key, frusta)))
            .collect();
        self.frame += 1;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shadow::views::Rect;

    fn one() -> Vec<FaceFrustum> {
        vec![FaceFrustum {
            face: 0,
            rect: Rect::FACE,
            cell: Rect::FACE,
            size: 64,
        }]
    }

    #[test]
    fn frusta_are_kept_for_their_key_and_chosen_again_now_and_then() {
        let mut kept = KeptFrusta::default();
        let mut kept_frames = 0;
        for _ in 0..(4 * RECHECK_EVERY) {
            if kept.get(3, 7).is_some() {
                kept_frames += 1;
            }
            assert!(kept.get(3, 8).is_none(), "another key");
            kept.record([(3, 7, one())]);
        }
        // Every frame but the first and one in RECHECK_EVERY.
        assert!((4 * (RECHECK_EVERY - 1) - 1..4 * RECHECK_EVERY).contains(&kept_frames));
        kept.record(std::iter::empty());
        assert!((0..RECHECK_EVERY).all(|_| {
            let none = kept.get(3, 7).is_none();
            kept.record(std::iter::empty());
            none
        }));
    }
}
