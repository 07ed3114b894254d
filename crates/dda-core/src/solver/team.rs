//! Two halves of the blocks worked at once through a whole iterative solve.
//!
//! A conjugate-gradient iteration makes three passes over the blocks (the product with
//! K, the descent with the preconditioner, the turn of the direction), each split into
//! the two halves of the blocks and followed by a sum over both. Handed to the thread
//! pool pass by pass (`rayon::join`), the second half often waited for a worker that
//! had gone to sleep between passes: on the 10,131-block column two threads took a CG
//! iteration in 0.56 ms against 0.82 ms on one, 1.4 times faster. Here a helper thread
//! lives as long as the solve and spins between passes: the stepping thread posts a
//! [`Phase`], works its half, and waits for the helper's sum, which it adds to its own
//! in a fixed order: 0.43 ms against 0.78 ms on one thread, 1.8 times. Each half's
//! arithmetic is the same on one thread or two, so the results are the same bits either
//! way.

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Mutex, PoisonError};

/// One pass over a half of the blocks (see `solver::iterative`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Phase {
    /// The inverses of the diagonal blocks that changed: the preconditioner.
    Invert,
    /// r = F - K x and z = D^-1 r; the sum is r . z.
    Residual,
    /// w = I^-1 r; the sum is r . w, the bound's B.
    Bound,
    /// p = z (a restart, `None`) or p = z + beta p.
    Turn(Option<f64>),
    /// q = K p; the sum is p . q.
    Product,
    /// x += alpha p, r -= alpha q, z = D^-1 r; the sum is r . z.
    Descend(f64),
}

/// The two halves of a solve, on one thread or two.
pub(super) enum Team<'a> {
    /// The stepping thread works both halves, the first then the second.
    Alone(&'a mut (dyn FnMut(Phase) -> f64 + Send)),
    /// A helper thread works the second half.
    Pair(&'a Link),
}

impl Team<'_> {
    /// Runs `phase` over both halves, the first by `first`, and returns the first half's
    /// sum plus the second's.
    pub(super) fn run(&mut self, phase: Phase, first: impl FnOnce(Phase) -> f64) -> f64 {
        match self {
            Team::Alone(second) => {
                let s0 = first(phase);
                s0 + second(phase)
            }
            Team::Pair(link) => {
                link.post(phase);
                let s0 = first(phase);
                s0 + link.wait()
            }
        }
    }
}

/// Runs `body` with a team whose second half is `second`: on a helper thread when
/// `threads` is set and the thread pool has two threads or more, else on this one.
pub(super) fn with_team<R>(
    threads: bool,
    mut second: impl FnMut(Phase) -> f64 + Send,
    body: impl FnOnce(&mut Team) -> R,
) -> R {
    if !(threads && pool_threads() >= 2) {
        return body(&mut Team::Alone(&mut second));
    }
    let link = Link::default();
    std::thread::scope(|s| {
        s.spawn(|| {
            // Marks the helper gone however it ends, so that the stepping thread never
            // waits for it in vain.
            let _gone = Flag(&link.gone);
            let mut seen = 0;
            while let Some(phase) = link.next(&mut seen) {
                let sum = second(phase);
                link.result.store(sum.to_bits(), Ordering::Relaxed);
                link.done.store(seen, Ordering::Release);
            }
        });
        // Closes the link however `body` ends (a panic included), so that the helper
        // stops and the scope can end.
        let _close = Flag(&link.closed);
        body(&mut Team::Pair(&link))
    })
}

/// Threads of the pool the solve runs in.
fn pool_threads() -> usize {
    #[cfg(feature = "rayon")]
    return rayon::current_num_threads();
    #[cfg(not(feature = "rayon"))]
    1
}

/// What the stepping thread and the helper share: the phase posted, how many phases were
/// posted and done, the last one's sum, and whether either side has ended.
#[derive(Default)]
pub(super) struct Link {
    phase: Mutex<Option<Phase>>,
    posted: AtomicU64,
    done: AtomicU64,
    result: AtomicU64,
    closed: AtomicBool,
    gone: AtomicBool,
}

impl Link {
    /// Posts `phase` to the helper.
    fn post(&self, phase: Phase) {
        *self.phase.lock().unwrap_or_else(PoisonError::into_inner) = Some(phase);
        self.posted.fetch_add(1, Ordering::Release);
    }

    /// Waits for the helper to finish the phase last posted; returns its sum.
    fn wait(&self) -> f64 {
        let posted = self.posted.load(Ordering::Relaxed);
        spin_until(|| {
            self.done.load(Ordering::Acquire) == posted || self.gone.load(Ordering::Acquire)
        });
        if self.done.load(Ordering::Acquire) != posted {
            panic!("the iterative solve's helper thread ended before its half was done");
        }
        f64::from_bits(self.result.load(Ordering::Relaxed))
    }

    /// The helper's side: waits for the next phase after the `seen`-th (counting it
    /// seen), or None once the link is closed.
    fn next(&self, seen: &mut u64) -> Option<Phase> {
        spin_until(|| {
            self.posted.load(Ordering::Acquire) > *seen || self.closed.load(Ordering::Acquire)
        });
        if self.posted.load(Ordering::Acquire) == *seen {
            return None;
        }
        *seen += 1;
        *self.phase.lock().unwrap_or_else(PoisonError::into_inner)
    }
}

/// Sets its flag when dropped.
struct Flag<'a>(&'a AtomicBool);

impl Drop for Flag<'_> {
    fn drop(&mut self) {
        self.0.store(true, Ordering::Release);
    }
}

/// Spins until `ready`, yielding the processor after the first few thousand tries (a
/// pass takes tens of microseconds; a machine with fewer cores than threads is then not
/// held up by the spinning).
fn spin_until(ready: impl Fn() -> bool) {
    let mut tries = 0u32;
    while !ready() {
        if tries < 1 << 14 {
            std::hint::spin_loop();
            tries += 1;
        } else {
            std::thread::yield_now();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A team's sums are the first half's plus the second's, on one thread or two; and a
    /// body that panics on two threads ends the helper and the call (it does not hang).
    #[test]
    fn a_team_adds_both_halves_and_ends_with_its_body() {
        let sums = |threads: bool| {
            let mut seen = Vec::new();
            let second = |phase: Phase| match phase {
                Phase::Descend(a) => 2.0 * a,
                _ => 1.0,
            };
            with_team(threads, second, |team| {
                for k in 0..50 {
                    seen.push(team.run(Phase::Descend(k as f64), |_| 0.5));
                }
            });
            seen
        };
        let want: Vec<f64> = (0..50).map(|k| 0.5 + 2.0 * k as f64).collect();
        #[cfg(feature = "rayon")]
        let two = rayon::ThreadPoolBuilder::new()
            .num_threads(2)
            .build()
            .expect("a pool of two threads")
            .install(|| {
                let ended = std::panic::catch_unwind(|| {
                    with_team(
                        true,
                        |_| 0.0,
                        |team| {
                            team.run(Phase::Product, |_| 0.0);
                            panic!("the body fails");
                        },
                    )
                });
                assert!(ended.is_err());
                sums(true)
            });
        #[cfg(not(feature = "rayon"))]
        let two = sums(true);
        assert_eq!(two, want);
        assert_eq!(sums(false), want);
    }
}
