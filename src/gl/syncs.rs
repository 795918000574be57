//! Counts every place the GL layer makes the CPU wait for the GPU ([`Syncs`]), so that a frame
//! reports its waits and a test can assert there are none. Counted per thread: a GL context is
//! current on one thread, and tests draw on several at once.

use crate::frame::Syncs;
use glow::HasContext;
use std::cell::Cell;

/// One kind of wait.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SyncKind {
    ReadBack,
    Finish,
    QueryRead,
    FenceWait,
    ErrorCheck,
}

thread_local! {
    static COUNTED: Cell<Syncs> = Cell::new(Syncs::default());
}

/// Records one wait of `kind` on this thread.
pub fn count(kind: SyncKind) {
    COUNTED.with(|c| {
        let mut s = c.get();
        let n = match kind {
            SyncKind::ReadBack => &mut s.read_backs,
            SyncKind::Finish => &mut s.finishes,
            SyncKind::QueryRead => &mut s.query_reads,
            SyncKind::FenceWait => &mut s.fence_waits,
            SyncKind::ErrorCheck => &mut s.error_checks,
        };
        *n = n.wrapping_add(1);
        c.set(s);
    });
}

/// Waits for every command sent so far (`glFinish`), counted.
pub fn finish(gl: &glow::Context) {
    // SAFETY: glFinish has no preconditions and changes no state.
    unsafe { gl.finish() };
    count(SyncKind::Finish);
}

/// A point in the GL's command stream (`glFenceSync`): the caller that needs to know when a
/// frame's work is done (bench's latency, a bound on frames in flight) waits for it, the frame
/// itself never does.
#[derive(Debug)]
pub struct Fence(glow::Fence);

impl Fence {
    /// A fence after every command sent so far; flushed, so that a wait on it ends.
    pub fn insert(gl: &glow::Context) -> Result<Fence, String> {
        // SAFETY: glFenceSync with the only condition GL defines; the flush has no preconditions.
        unsafe {
            let f = gl.fence_sync(glow::SYNC_GPU_COMMANDS_COMPLETE, 0)?;
            gl.flush();
            Ok(Fence(f))
        }
    }

    /// Waits until the GL has run every command before the fence (counted), and deletes it.
    pub fn wait(self, gl: &glow::Context) {
        count(SyncKind::FenceWait);
        // A second's timeout per try, retried: a frame may take longer on a software rasteriser,
        // and only a lost context makes the wait fail.
        loop {
            // SAFETY: the fence is live (deleted only below).
            let r = unsafe {
                gl.client_wait_sync(self.0, glow::SYNC_FLUSH_COMMANDS_BIT, 1_000_000_000)
            };
            if r != glow::TIMEOUT_EXPIRED {
                break;
            }
        }
        self.delete(gl);
    }

    /// Deletes the fence without waiting for it.
    pub fn delete(self, gl: &glow::Context) {
        // SAFETY: no one else holds the fence.
        unsafe { gl.delete_sync(self.0) };
    }
}

/// A bound on the lights' passes the GL holds queued (`Plan::lights_per_fence`): the lights
/// are sent in groups of `group`, a fence after each, and before a group is sent past the
/// next the one before it is waited for (counted), so that at most two groups are queued.
/// A CPU rasteriser bins what it is sent ahead of its threads, and a frame of many lights
/// binned whole held gigabytes (docs/reproduce.md). Groups rather than single lights: each
/// fence flushes, and a flush per light cost a frame of 64 small lit passes a quarter more on
/// llvmpipe. 0 never waits.
pub struct LightQueue<'gl> {
    gl: &'gl glow::Context,
    group: u32,
    sent: u32,
    /// The fence after the last group sent, not yet waited for.
    last: Option<Fence>,
}

impl<'gl> LightQueue<'gl> {
    pub fn new(gl: &'gl glow::Context, group: u32) -> LightQueue<'gl> {
        LightQueue {
            gl,
            group,
            sent: 0,
            last: None,
        }
    }

    /// A light's passes were sent: at the end of a group, a fence, and a wait until the group
    /// before the last has run.
    pub fn light_sent(&mut self) -> Result<(), String> {
        if self.group == 0 {
            return Ok(());
        }
        self.sent += 1;
        if !self.sent.is_multiple_of(self.group) {
            return Ok(());
        }
        if let Some(before) = self.last.replace(Fence::insert(self.gl)?) {
            before.wait(self.gl);
        }
        Ok(())
    }
}

impl Drop for LightQueue<'_> {
    fn drop(&mut self) {
        if let Some(f) = self.last.take() {
            f.delete(self.gl);
        }
    }
}

/// Every wait counted on this thread so far: take one before and one after, and
/// [`Syncs::since`] says what lay between.
pub fn counted() -> Syncs {
    COUNTED.with(Cell::get)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_kind_counts_in_its_own_field_and_since_subtracts() {
        let before = counted();
        count(SyncKind::ReadBack);
        count(SyncKind::ReadBack);
        count(SyncKind::Finish);
        count(SyncKind::QueryRead);
        count(SyncKind::FenceWait);
        count(SyncKind::ErrorCheck);
        let d = counted().since(&before);
        assert_eq!(
            d,
            Syncs {
                read_backs: 2,
                finishes: 1,
                query_reads: 1,
                fence_waits: 1,
                error_checks: 1,
            }
        );
        assert_eq!(d.total(), 6);
        assert_eq!(
            d.describe(),
            "6 (2 read-backs, 1 finish, 1 query read, 1 fence wait, 1 error check)"
        );
        assert_eq!(Syncs::default().describe(), "0");
    }
}
