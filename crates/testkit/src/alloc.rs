//! A counting global allocator that measures the heap of one call, even in a test binary whose
//! other tests run (and allocate) at the same time.
//!
//! A test binary installs it with `#[global_allocator] static A: Counting = Counting;`, takes
//! [`alone`] for each measuring test's body and measures a call with [`peak_during`].
//!
//! Only allocations made on a *measured* thread are counted: the thread that calls
//! [`peak_during`] (while it does) and the workers of the rayon pool [`peak_during`] runs the call
//! in. Each block carries a header saying whether it was counted, so a counted block freed on
//! any thread is subtracted and an uncounted one never is: what the other tests of the binary
//! allocate and free meanwhile, on their own threads, does not reach the counters. Threads the
//! measured call starts itself with `std::thread` are not measured (rayon work is).

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Mutex, MutexGuard, OnceLock};

/// The system allocator, counting the bytes held by blocks allocated on measured threads and
/// their peak.
pub struct Counting;

static HELD: AtomicUsize = AtomicUsize::new(0);
static PEAK: AtomicUsize = AtomicUsize::new(0);
static MEASURING: Mutex<()> = Mutex::new(());

thread_local! {
    // A `const` initialiser and a type without `Drop`: reading it never allocates (the allocator
    // reads it) and never fails, not even while the thread exits.
    static MEASURED: Cell<bool> = const { Cell::new(false) };
}

/// The header in front of every block: `COUNTED` when its bytes are in `HELD`.
type Header = usize;
const COUNTED: Header = 1;
const UNCOUNTED: Header = 0;

fn measured() -> bool {
    MEASURED.try_with(Cell::get).unwrap_or(false)
}

fn grew(bytes: usize) {
    let now = HELD.fetch_add(bytes, Ordering::SeqCst) + bytes;
    PEAK.fetch_max(now, Ordering::SeqCst);
}

fn shrank(bytes: usize) {
    HELD.fetch_sub(bytes, Ordering::SeqCst);
}

/// The layout asked of `System` for a block of `layout` with its header, and the offset of the
/// caller's bytes in it. The offset is the alignment (at least a header's size and alignment), so
/// the caller's pointer keeps `layout`'s alignment and the header, just before it, is aligned.
fn padded(layout: Layout) -> Option<(Layout, usize)> {
    let align = layout.align().max(align_of::<Header>()).max(size_of::<Header>());
    let size = layout.size().checked_add(align)?;
    Some((Layout::from_size_align(size, align).ok()?, align))
}

/// Writes the header of a block `System` returned at `base` (or passes on its null) and returns
/// the caller's pointer.
///
/// # Safety
/// `base` is null or a block of `padded(layout)`'s layout.
unsafe fn tagged(base: *mut u8, offset: usize, header: Header) -> *mut u8 {
    if base.is_null() {
        return base;
    }
    // SAFETY: the block is `offset` bytes longer than the caller asked; the header's bytes lie
    // just before the caller's pointer, within the block, and are aligned (`padded`).
    unsafe {
        let p = base.add(offset);
        p.cast::<Header>().sub(1).write(header);
        p
    }
}

/// The block `System` allocated for the caller's `ptr`, and its header.
///
/// # Safety
/// `ptr` came from this allocator with a layout whose padding is `offset`.
unsafe fn block_of(ptr: *mut u8, offset: usize) -> (*mut u8, Header) {
    // SAFETY: `tagged` put the header just before `ptr` and the block's start `offset` before it.
    unsafe { (ptr.sub(offset), ptr.cast::<Header>().sub(1).read()) }
}

// SAFETY: every block is a `System` block `padded` bytes longer than asked, aligned to at least
// the alignment asked; the caller's pointer is `offset` bytes in, so it keeps that alignment and
// has `layout.size()` bytes of its own. Deallocation and reallocation recompute the same padded
// layout from the caller's layout, as `System` requires. The counters are updated beside.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let Some((outer, offset)) = padded(layout) else { return std::ptr::null_mut() };
        let header = if measured() { COUNTED } else { UNCOUNTED };
        // SAFETY: `outer` has a non-zero size (at least `offset`).
        let p = unsafe { tagged(System.alloc(outer), offset, header) };
        if !p.is_null() && header == COUNTED {
            grew(layout.size());
        }
        p
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        let Some((outer, offset)) = padded(layout) else { return std::ptr::null_mut() };
        let header = if measured() { COUNTED } else { UNCOUNTED };
        // SAFETY: as in `alloc`; the header overwrites zeros of the padding only.
        let p = unsafe { tagged(System.alloc_zeroed(outer), offset, header) };
        if !p.is_null() && header == COUNTED {
            grew(layout.size());
        }
        p
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        let (outer, offset) = padded(layout).expect("the layout was padded when it was allocated");
        // SAFETY: `ptr` came from `alloc`, `alloc_zeroed` or `realloc` with this layout.
        let (base, header) = unsafe { block_of(ptr, offset) };
        // SAFETY: `base` is the `System` block of layout `outer`.
        unsafe { System.dealloc(base, outer) };
        if header == COUNTED {
            shrank(layout.size());
        }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        let (outer, offset) = padded(layout).expect("the layout was padded when it was allocated");
        let Some(outer_size) = new_size.checked_add(offset) else { return std::ptr::null_mut() };
        if Layout::from_size_align(outer_size, outer.align()).is_err() {
            return std::ptr::null_mut();
        }
        // SAFETY: `ptr` came from this allocator with `layout`.
        let (base, before) = unsafe { block_of(ptr, offset) };
        // A block grown on a measured thread is counted from then on; a counted one stays counted.
        let after = if before == COUNTED || measured() { COUNTED } else { UNCOUNTED };
        // SAFETY: `base` is the `System` block of layout `outer`; the new size is valid with its
        // alignment (checked above) and non-zero. `System` copies the header with the bytes.
        let p = unsafe { tagged(System.realloc(base, outer, outer_size), offset, after) };
        if !p.is_null() {
            if before == COUNTED {
                shrank(layout.size());
            }
            if after == COUNTED {
                grew(new_size);
            }
        }
        p
    }
}

/// Holds every other measuring test of the binary off: each test that measures takes it for its
/// whole body, so its measurements and what it frees afterwards do not overlap another's.
pub fn alone() -> MutexGuard<'static, ()> {
    MEASURING.lock().unwrap_or_else(|e| e.into_inner())
}

/// Marks the current thread measured until dropped.
struct Measured;

impl Measured {
    fn start() -> Measured {
        MEASURED.with(|m| m.set(true));
        Measured
    }
}

impl Drop for Measured {
    fn drop(&mut self) {
        MEASURED.with(|m| m.set(false));
    }
}

/// The rayon pool measured calls run in, as many threads as the global pool; every worker is a
/// measured thread. One pool for the process: its workers and what they keep (thread-local
/// scratch) outlive a call, as the global pool's do, rather than being freed during the next one.
fn pool() -> &'static rayon::ThreadPool {
    static POOL: OnceLock<rayon::ThreadPool> = OnceLock::new();
    POOL.get_or_init(|| {
        let pool = rayon::ThreadPoolBuilder::new()
            .thread_name(|i| format!("measured-{i}"))
            .start_handler(|_| MEASURED.with(|m| m.set(true)))
            .build()
            .expect("a rayon pool for measured calls");
        // Every worker started (and allocated what a worker holds) before any call is measured.
        pool.broadcast(|_| ());
        pool
    })
}

/// `f`'s result and the most heap bytes it held at once above what was held before it. `f` runs
/// in a rayon pool of measured threads (its rayon work too); call it while holding [`alone`], in
/// a binary whose global allocator is [`Counting`] (elsewhere the peak reads 0).
pub fn peak_during<T: Send>(f: impl FnOnce() -> T + Send) -> (T, usize) {
    let pool = pool();
    let _measured = Measured::start();
    let base = HELD.load(Ordering::SeqCst);
    PEAK.store(base, Ordering::SeqCst);
    let result = pool.install(f);
    (result, PEAK.load(Ordering::SeqCst).saturating_sub(base))
}
