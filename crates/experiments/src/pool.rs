//! A small thread pool for independent runs: `jobs` workers take the next index from
//! an atomic counter; results come back in index order, whatever the number of
//! workers or the order they finish in.
//!
//! Each item runs on a fresh thread: faer's AVX-512 matrix kernels (the filter's
//! covariance products) leave the upper vector register state dirty in the thread that
//! navigated, and the simulator's SSE code then runs about 4x slower in that thread
//! (measured: 0.4 s -> 2.1 s per lap simulated).

use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

/// What a worker does after an item: go on, or hand out no more work.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Next {
    Continue,
    Stop,
}

/// `f(i)` for `i` in `0..n` on `jobs` workers (at least 1), each call on a fresh
/// thread; a call that panics gives `on_panic(i)`. `done(i, &r)` is called as each
/// item finishes (in the order they finish, one at a time) and may stop the pool.
/// Returns the results in index order; `None` for the items not run after a stop.
pub(crate) fn run_indexed<R: Send>(
    n: usize,
    jobs: usize,
    f: impl Fn(usize) -> R + Sync,
    on_panic: impl Fn(usize) -> R + Sync,
    done: impl Fn(usize, &R) -> Next + Sync,
) -> Vec<Option<R>> {
    let next = AtomicUsize::new(0);
    let out: Mutex<Vec<Option<R>>> = Mutex::new((0..n).map(|_| None).collect());
    std::thread::scope(|s| {
        for _ in 0..jobs.max(1).min(n) {
            s.spawn(|| loop {
                let i = next.fetch_add(1, Ordering::SeqCst);
                if i >= n {
                    break;
                }
                let r =
                    std::thread::scope(|t| t.spawn(|| f(i)).join().unwrap_or_else(|_| on_panic(i)));
                let mut out = out.lock().unwrap_or_else(|p| p.into_inner());
                let stop = done(i, &r) == Next::Stop;
                out[i] = Some(r);
                drop(out);
                if stop {
                    next.store(n, Ordering::SeqCst);
                    break;
                }
            });
        }
    });
    out.into_inner().unwrap_or_else(|p| p.into_inner())
}
