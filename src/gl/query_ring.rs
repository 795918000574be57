//! Timer queries read frames after they were issued, without waiting: each frame's queries join
//! a ring, and a frame takes the results of the latest earlier frame whose queries the GL has
//! finished (a poll of `GL_QUERY_RESULT_AVAILABLE` on its last query, which never blocks).
//! Frames older than that are dropped unread; a ring that fills (the GL far behind) drops its
//! oldest. The bookkeeping is free of GL: the timer hands it the poll and the read.

use std::collections::VecDeque;

/// The most frames whose queries wait to be read: more than a GPU runs behind in practice.
pub const RING_FRAMES: usize = 4;

/// One frame's queries, by what they timed.
pub struct PendingFrame<K, Q> {
    pub queries: Vec<(K, Q)>,
}

/// Frames whose query results have not been read, oldest first.
pub struct QueryRing<K, Q> {
    frames: VecDeque<PendingFrame<K, Q>>,
}

impl<K, Q> Default for QueryRing<K, Q> {
    fn default() -> Self {
        QueryRing {
            frames: VecDeque::new(),
        }
    }
}

/// What [`QueryRing::push_and_collect`] gives back: the latest finished frame's results (none
/// when no earlier frame has finished), how many frames back that frame was, and the queries
/// free for reuse (read, dropped unread, or pushed out of a full ring).
pub struct Collected<K, Q> {
    pub results: Vec<(K, f64)>,
    pub frames_ago: usize,
    pub freed: Vec<Q>,
}

impl<K, Q: Copy> QueryRing<K, Q> {
    /// Adds this frame's queries, then collects: the newest frame for which `done(last query)`
    /// holds is read with `read`, every frame before it dropped.
    pub fn push_and_collect(
        &mut self,
        frame: Vec<(K, Q)>,
        mut done: impl FnMut(Q) -> bool,
        mut read: impl FnMut(Q) -> f64,
    ) -> Collected<K, Q> {
        let mut freed = Vec::new();
        self.frames.push_back(PendingFrame { queries: frame });
        while self.frames.len() > RING_FRAMES {
            let old = self.frames.pop_front().expect("longer than the limit");
            freed.extend(old.queries.into_iter().map(|(_, q)| q));
        }
        // The newest finished frame, not this one: this frame has only just been sent.
        let newest_done = (0..self.frames.len() - 1).rev().find(|&i| {
            let f = &self.frames[i];
            f.queries.last().is_none_or(|&(_, q)| done(q))
        });
        let Some(i) = newest_done else {
            return Collected {
                results: Vec::new(),
                frames_ago: 0,
                freed,
            };
        };
        let frames_ago = self.frames.len() - 1 - i;
        let mut results = Vec::new();
        for k in 0..=i {
            let f = self.frames.pop_front().expect("index within the ring");
            for (key, q) in f.queries {
                if k == i {
                    results.push((key, read(q)));
                }
                freed.push(q);
            }
        }
        Collected {
            results,
            frames_ago,
            freed,
        }
    }

    /// Every query still waiting, for deletion.
    pub fn drain(&mut self) -> Vec<Q> {
        self.frames
            .drain(..)
            .flat_map(|f| f.queries.into_iter().map(|(_, q)| q))
            .collect()
    }

    pub fn len(&self) -> usize {
        self.frames.len()
    }

    pub fn is_empty(&self) -> bool {
        self.frames.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Queries are numbers; a query is done when it is below `done_below`, and reads as itself.
    fn collect(
        ring: &mut QueryRing<&'static str, u32>,
        frame: Vec<(&'static str, u32)>,
        done_below: u32,
    ) -> Collected<&'static str, u32> {
        ring.push_and_collect(frame, |q| q < done_below, f64::from)
    }

    #[test]
    fn a_frame_reads_the_newest_earlier_frame_that_finished_and_drops_the_older() {
        let mut ring = QueryRing::default();
        // Frame 1 (queries 10, 11): nothing earlier, nothing read.
        let c = collect(&mut ring, vec![("base", 10), ("lit", 11)], 0);
        assert!(c.results.is_empty() && c.freed.is_empty());
        // Frame 2: frame 1 not finished yet.
        let c = collect(&mut ring, vec![("base", 20), ("lit", 21)], 11);
        assert!(c.results.is_empty());
        assert_eq!(ring.len(), 2);
        // Frame 3: frames 1 and 2 finished; 2 is read, 1 dropped unread, 3 waits.
        let c = collect(&mut ring, vec![("base", 30)], 30);
        assert_eq!(c.results, vec![("base", 20.0), ("lit", 21.0)]);
        assert_eq!(c.frames_ago, 1);
        assert_eq!(c.freed, vec![10, 11, 20, 21]);
        assert_eq!(ring.len(), 1);
    }

    #[test]
    fn this_frame_is_never_read_at_once_and_a_full_ring_drops_its_oldest() {
        let mut ring = QueryRing::default();
        // Everything reports done, yet the frame just sent is not read.
        let c = collect(&mut ring, vec![("base", 1)], u32::MAX);
        assert!(c.results.is_empty());
        // Nothing ever finishes: the ring keeps RING_FRAMES frames and frees the rest.
        let mut ring = QueryRing::default();
        let mut freed = Vec::new();
        for q in 0..10 {
            freed.extend(collect(&mut ring, vec![("base", q)], 0).freed);
        }
        assert_eq!(ring.len(), RING_FRAMES);
        assert_eq!(freed, (0..10 - RING_FRAMES as u32).collect::<Vec<_>>());
        assert_eq!(ring.drain().len(), RING_FRAMES);
    }
}
