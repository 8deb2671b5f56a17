//! A global allocator that counts: the largest single request and the peak of live bytes
//! since the last [`reset`], so that the fuzz loop can tell when a reader allocates what a
//! header declares rather than what the file holds. Requests above [`HARD_LIMIT_BYTES`] fail
//! (Rust then aborts the process, which the fuzz driver records as a crash with its input).

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

/// A single request larger than this fails outright instead of reaching the system.
pub const HARD_LIMIT_BYTES: usize = 4 << 30;

static LIVE: AtomicUsize = AtomicUsize::new(0);
static PEAK: AtomicUsize = AtomicUsize::new(0);
static LARGEST: AtomicUsize = AtomicUsize::new(0);

/// The counting allocator ([`System`] underneath).
pub struct Counting;

fn grew(size: usize) {
    let live = LIVE.fetch_add(size, Ordering::Relaxed) + size;
    PEAK.fetch_max(live, Ordering::Relaxed);
    LARGEST.fetch_max(size, Ordering::Relaxed);
}

// SAFETY: every method forwards to `System` with the caller's layout and pointer unchanged;
// the only additions are relaxed atomic counters and refusing (null) oversized requests,
// which `GlobalAlloc` allows.
#[allow(unsafe_code)]
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        if layout.size() > HARD_LIMIT_BYTES {
            LARGEST.fetch_max(layout.size(), Ordering::Relaxed);
            return std::ptr::null_mut();
        }
        // SAFETY: forwarded as is (see the impl).
        let pointer = unsafe { System.alloc(layout) };
        if !pointer.is_null() {
            grew(layout.size());
        }
        pointer
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        if layout.size() > HARD_LIMIT_BYTES {
            LARGEST.fetch_max(layout.size(), Ordering::Relaxed);
            return std::ptr::null_mut();
        }
        // SAFETY: forwarded as is (see the impl).
        let pointer = unsafe { System.alloc_zeroed(layout) };
        if !pointer.is_null() {
            grew(layout.size());
        }
        pointer
    }

    unsafe fn dealloc(&self, pointer: *mut u8, layout: Layout) {
        // SAFETY: forwarded as is (see the impl).
        unsafe { System.dealloc(pointer, layout) };
        LIVE.fetch_sub(layout.size(), Ordering::Relaxed);
    }

    unsafe fn realloc(&self, pointer: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        if new_size > HARD_LIMIT_BYTES {
            LARGEST.fetch_max(new_size, Ordering::Relaxed);
            return std::ptr::null_mut();
        }
        // SAFETY: forwarded as is (see the impl).
        let moved = unsafe { System.realloc(pointer, layout, new_size) };
        if !moved.is_null() {
            LIVE.fetch_sub(layout.size(), Ordering::Relaxed);
            grew(new_size);
        }
        moved
    }
}

/// What was allocated since the last [`reset`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Usage {
    /// The largest single request, bytes.
    pub largest_bytes: usize,
    /// The most bytes live at once, over what was live at the reset, bytes.
    pub peak_growth_bytes: usize,
}

/// Starts a measurement; returns the live bytes at its start (pass them to [`usage`]).
pub fn reset() -> usize {
    let live = LIVE.load(Ordering::Relaxed);
    PEAK.store(live, Ordering::Relaxed);
    LARGEST.store(0, Ordering::Relaxed);
    live
}

/// What was allocated since [`reset`] returned `live_at_reset`.
pub fn usage(live_at_reset: usize) -> Usage {
    Usage {
        largest_bytes: LARGEST.load(Ordering::Relaxed),
        peak_growth_bytes: PEAK.load(Ordering::Relaxed).saturating_sub(live_at_reset),
    }
}
