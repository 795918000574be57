//! Which neighbouring caster chunks a light's stencil pass draws as one piece
//! (`plan.merge_pieces`).
//!
//! The planner cuts large connected casters into chunks so that it can cull them one by one; each
//! chunk's volume is closed on its own, so along every cut both chunks extrude a side, one the
//! other's mirror. The two cancel in the count but are both rasterised: on the benchmark maps
//! these seam sides were 30–55% of all volume fragments. Two halves of a cut that a light keeps
//! with the same counting can be drawn as one piece without them. Merging widens the piece's
//! rectangle to the union of the halves' (its draw is scissored there, and its depth clip is
//! fitted there), so halves whose rectangles lie apart are left as they are.

use super::scissor::Scissor;
use crate::shadow::volume::{ChunkNode, Counting};
use std::collections::HashMap;

/// A kept chunk as the merge sees it: how its volume is counted and where its draw may change
/// counts.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct KeptChunk {
    pub counting: Counting,
    pub rect: Scissor,
}

/// The largest share by which a merged piece's rectangle may exceed the halves' rectangles
/// together: above 1, their union covers pixels neither half's draw touched.
pub const MERGE_SLACK: f64 = 1.0;

/// The spans of consecutive chunks `first..end` (two or more) to draw as one piece each: the
/// largest cuts of `tree` (children before parents, as [`crate::shadow::volume::CasterGroup`]
/// keeps it) whose chunks are all kept, all counted alike, and whose halves' rectangles overlap
/// enough that their union is at most [`MERGE_SLACK`] times their areas together. `kept(i)` says
/// how chunk `i` is drawn (None: not drawn this frame). Disjoint, in tree order.
pub fn merged_spans(
    tree: &[ChunkNode],
    kept: impl Fn(usize) -> Option<KeptChunk>,
) -> Vec<(usize, usize)> {
    // What each span merged so far draws as; a cut's halves are a chunk or an earlier cut.
    let mut merged: HashMap<(usize, usize), KeptChunk> = HashMap::new();
    let half = |merged: &HashMap<(usize, usize), KeptChunk>, first: usize, end: usize| {
        if end - first == 1 {
            kept(first)
        } else {
            merged.get(&(first, end)).copied()
        }
    };
    let mut spans: Vec<(usize, usize)> = Vec::new();
    for n in tree {
        let (Some(a), Some(b)) = (half(&merged, n.first, n.mid), half(&merged, n.mid, n.end))
        else {
            continue;
        };
        let union = a.rect.union(&b.rect);
        let together = (a.rect.area() + b.rect.area()) as f64;
        if a.counting != b.counting || union.area() as f64 > MERGE_SLACK * together {
            continue;
        }
        merged.insert(
            (n.first, n.end),
            KeptChunk {
                counting: a.counting,
                rect: union,
            },
        );
        // A cut's halves come before it: the spans it covers are dropped for it.
        spans.retain(|&(f, e)| !(n.first <= f && e <= n.end));
        spans.push((n.first, n.end));
    }
    spans
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rect(x: i32, y: i32, width: i32, height: i32) -> Scissor {
        Scissor {
            x,
            y,
            width,
            height,
        }
    }

    /// Eight chunks cut in halves three times, children before parents.
    fn tree() -> Vec<ChunkNode> {
        let node = |first, mid, end| ChunkNode { first, mid, end };
        vec![
            node(0, 1, 2),
            node(2, 3, 4),
            node(0, 2, 4),
            node(4, 5, 6),
            node(6, 7, 8),
            node(4, 6, 8),
            node(0, 4, 8),
        ]
    }

    #[test]
    fn overlapping_kept_chunks_merge_up_to_the_largest_cut() {
        let same = |_| {
            Some(KeptChunk {
                counting: Counting::ZPass,
                rect: rect(10, 10, 100, 80),
            })
        };
        assert_eq!(merged_spans(&tree(), same), vec![(0, 8)]);
    }

    #[test]
    fn a_missing_chunk_a_different_counting_or_distant_rectangles_stop_a_merge() {
        let kept = |i: usize| -> Option<KeptChunk> {
            let near = rect(10 + i as i32, 10, 100, 80);
            match i {
                // Not drawn this frame.
                1 => None,
                // Counted depth-fail.
                3 => Some(KeptChunk {
                    counting: Counting::ZFail,
                    rect: near,
                }),
                // Its rectangle far from its sibling's: the union would be mostly empty.
                5 => Some(KeptChunk {
                    counting: Counting::ZPass,
                    rect: rect(500, 400, 20, 20),
                }),
                _ => Some(KeptChunk {
                    counting: Counting::ZPass,
                    rect: near,
                }),
            }
        };
        // 0..2 has chunk 1 missing, 2..4 mixes countings, 4..6 lies apart; only 6..8 merges.
        assert_eq!(merged_spans(&tree(), kept), vec![(6, 8)]);
    }

    #[test]
    fn the_union_may_not_exceed_the_halves_areas_together() {
        let node = [ChunkNode {
            first: 0,
            mid: 1,
            end: 2,
        }];
        let at = |gap: i32| {
            move |i: usize| {
                Some(KeptChunk {
                    counting: Counting::ZPass,
                    rect: rect(i as i32 * (10 + gap), 0, 10, 10),
                })
            }
        };
        // Side by side: union 200 = 100 + 100.
        assert_eq!(merged_spans(&node, at(0)), vec![(0, 2)]);
        // One pixel apart: union 210 > 200.
        assert!(merged_spans(&node, at(1)).is_empty());
    }
}
