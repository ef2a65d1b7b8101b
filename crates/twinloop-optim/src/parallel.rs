//! The thread pool the fits and batches share (rayon's work-stealing pool): where it
//! runs, and scratch space for objectives that need buffers.
//!
//! Results never depend on the number of threads: every parallel loop here writes
//! each item's result into its own slot, and whatever is reduced (sums, the best
//! point, sorting) is reduced afterwards on one thread, in index order.

use std::sync::Mutex;

/// Run `f` with `threads` workers for the rayon calls inside it: 0 runs it on the
/// pool it is called from (rayon's global pool outside any: one worker per core, or
/// `RAYON_NUM_THREADS`), n > 0 on a pool of n workers (that one, if it is called
/// from a pool of n; else one spawned for the call: for work of milliseconds or
/// more). A pool the system refuses to start leaves `f` where it was called.
pub fn on_threads<R: Send>(threads: usize, f: impl FnOnce() -> R + Send) -> R {
    let inside = rayon::current_thread_index().is_some();
    if threads == 0 || (inside && rayon::current_num_threads() == threads) {
        return f();
    }
    match rayon::ThreadPoolBuilder::new().num_threads(threads).build() {
        Ok(pool) => pool.install(f),
        Err(_) => f(),
    }
}

/// The workers `threads` means to [`on_threads`]: itself, or every core when 0.
pub fn worker_threads(threads: usize) -> usize {
    if threads > 0 {
        threads
    } else {
        rayon::current_num_threads()
    }
}

/// Buffers for objectives evaluated in parallel: a call takes one (made by `make`
/// when none is free) and gives it back, so a fit allocates one per worker at most,
/// once, however many evaluations it runs. An objective must not read what an
/// earlier call left in its buffer (which call had it is not fixed).
pub struct Scratch<T> {
    free: Mutex<Vec<T>>,
    make: Box<dyn Fn() -> T + Send + Sync>,
}

impl<T> Scratch<T> {
    pub fn new(make: impl Fn() -> T + Send + Sync + 'static) -> Scratch<T> {
        Scratch {
            free: Mutex::new(Vec::new()),
            make: Box::new(make),
        }
    }

    /// `f` with a buffer of its own.
    pub fn with<R>(&self, f: impl FnOnce(&mut T) -> R) -> R {
        // A panic elsewhere cannot leave the list half changed (push and pop only).
        let taken = self.free.lock().unwrap_or_else(|e| e.into_inner()).pop();
        let mut t = taken.unwrap_or_else(|| (self.make)());
        let r = f(&mut t);
        self.free.lock().unwrap_or_else(|e| e.into_inner()).push(t);
        r
    }
}
