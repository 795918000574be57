//! Per-pass timing: GL_TIME_ELAPSED queries around each GPU pass, wall time for CPU stages.
//!
//! Without timer queries (see `gl/caps`), each pass is timed on the CPU between two glFinish calls,
//! which serialises the pipeline but still attributes time to the right pass. GL_TIMESTAMP is never
//! used: llvmpipe's is not accurate. Query objects are pooled so long runs create none. A frame
//! that wants its pass times without waiting for them (`finish_later`) gets the latest earlier
//! frame's whose queries are done (`query_ring`).

use super::query_ring::QueryRing;
use super::syncs::SyncKind;
use crate::plan::pass::{Clock, PassId, PassTime};
use glow::HasContext;
use std::time::Instant;

enum Span {
    Gpu(glow::Query),
    Cpu(Instant),
}

pub struct PassTimer {
    use_queries: bool,
    /// Whether timer queries work here (`use_queries` may be switched off for a frame).
    queries_work: bool,
    /// This frame times nothing (the CPU clock would need glFinish between passes).
    silent: bool,
    pool: Vec<glow::Query>,
    open: Option<(PassId, Span)>,
    gpu_done: Vec<(PassId, glow::Query)>,
    results: Vec<PassTime>,
    /// Frames' queries read later (`finish_later`).
    ring: QueryRing<PassId, glow::Query>,
}

impl PassTimer {
    pub fn new(use_queries: bool) -> PassTimer {
        PassTimer {
            use_queries,
            queries_work: use_queries,
            silent: false,
            pool: Vec::new(),
            open: None,
            gpu_done: Vec::new(),
            results: Vec::new(),
            ring: QueryRing::default(),
        }
    }

    /// Times with queries only where `allowed` (`gl.disable = timer_query`) and they work.
    pub fn allow_queries(&mut self, allowed: bool) {
        self.use_queries = allowed && self.queries_work;
    }

    pub fn uses_queries(&self) -> bool {
        self.use_queries
    }

    /// Starts a frame. `per_pass = false` times no pass: the frame then runs without the
    /// glFinish calls that serialise it (no timer queries) or the query reads that wait for
    /// its end (timer queries), and only its total is meaningful.
    pub fn start_frame(&mut self, per_pass: bool) {
        self.silent = !per_pass;
    }

    /// Starts timing the GPU work of pass `name`; ends any pass still open.
    pub fn begin(&mut self, gl: &glow::Context, name: PassId) {
        self.end(gl);
        if self.silent {
            return;
        }
        let span = if self.use_queries {
            let q = match self.pool.pop() {
                Some(q) => q,
                // SAFETY: creating a query object on a current context.
                None => match unsafe { gl.create_query() } {
                    Ok(q) => q,
                    Err(_) => {
                        self.use_queries = false;
                        self.queries_work = false;
                        return self.begin(gl, name);
                    }
                },
            };
            // SAFETY: no other TIME_ELAPSED query is active (end() closed it).
            unsafe { gl.begin_query(glow::TIME_ELAPSED, q) };
            Span::Gpu(q)
        } else {
            super::syncs::finish(gl);
            Span::Cpu(Instant::now())
        };
        self.open = Some((name, span));
    }

    /// Ends the open pass, if any.
    pub fn end(&mut self, gl: &glow::Context) {
        match self.open.take() {
            Some((name, Span::Gpu(q))) => {
                // SAFETY: this query was begun by begin().
                unsafe { gl.end_query(glow::TIME_ELAPSED) };
                self.gpu_done.push((name, q));
            }
            Some((name, Span::Cpu(t))) => {
                super::syncs::finish(gl);
                self.results.push(PassTime {
                    pass: name,
                    ms: t.elapsed().as_secs_f64() * 1e3,
                    clock: Clock::Cpu,
                });
            }
            None => {}
        }
    }

    /// Records a CPU-only stage (e.g. building shadow volumes).
    pub fn record_cpu(&mut self, name: PassId, ms: f64) {
        if self.silent {
            return;
        }
        self.results.push(PassTime {
            pass: name,
            ms,
            clock: Clock::Cpu,
        });
    }

    /// Closes the frame: waits for the query results and returns every pass in start order.
    pub fn finish(&mut self, gl: &glow::Context) -> Vec<PassTime> {
        self.end(gl);
        for (name, q) in self.gpu_done.drain(..) {
            // SAFETY: the query has ended; GL blocks until its result is available.
            let ns = unsafe { gl.get_query_parameter_u64(q, glow::QUERY_RESULT) };
            super::syncs::count(SyncKind::QueryRead);
            self.results.push(PassTime {
                pass: name,
                ms: ns as f64 / 1e6,
                clock: Clock::Gpu,
            });
            self.pool.push(q);
        }
        std::mem::take(&mut self.results)
    }

    /// Closes the frame without waiting: its CPU stages, and the GPU passes of the latest
    /// earlier frame whose queries the GL has finished (with how many frames back it was);
    /// this frame's queries wait in the ring. A result read once available does not wait, so
    /// nothing is counted.
    pub fn finish_later(&mut self, gl: &glow::Context) -> (Vec<PassTime>, usize) {
        self.end(gl);
        let frame = std::mem::take(&mut self.gpu_done);
        // SAFETY: polls and reads of ended queries; a poll never blocks, and a read only
        // follows a poll that said the result is there.
        let c = self.ring.push_and_collect(
            frame,
            |q| unsafe { gl.get_query_parameter_u32(q, glow::QUERY_RESULT_AVAILABLE) != 0 },
            |q| unsafe { gl.get_query_parameter_u64(q, glow::QUERY_RESULT) } as f64 / 1e6,
        );
        self.pool.extend(c.freed);
        let mut passes = std::mem::take(&mut self.results);
        passes.extend(c.results.into_iter().map(|(pass, ms)| PassTime {
            pass,
            ms,
            clock: Clock::Gpu,
        }));
        (passes, c.frames_ago)
    }

    pub fn delete(&mut self, gl: &glow::Context) {
        self.pool.extend(self.ring.drain());
        for q in self.pool.drain(..) {
            // SAFETY: pooled queries are not active.
            unsafe { gl.delete_query(q) };
        }
    }
}
