//! Two halves of the blocks worked at once through a whole iterative solve.
//!
//! A conjugate-gradient iteration makes three passes over the blocks (the product with
//! the scaled K, the descent, the turn of the direction), each split into
//! the two halves of the blocks and followed by a sum over both. Handed to the thread
//! pool pass by pass (`rayon::join`), the second half often waited for a worker that
//! had gone to sleep between passes: on the 10,131-block column two threads took a CG
//! iteration in 0.56 ms against 0.82 ms on one, 1.4 times faster. Here a helper thread
//! lives as long as the solve and waits between passes, spinning a while before it
//! parks: the stepping thread posts a [`Phase`], works its half, then works the second
//! half too if the helper has not taken it up (a helper that is not running, where more
//! threads run than there are cores, holds nothing up), or waits for the helper's sum;
//! the two sums are added in a fixed order. 0.45 ms against 0.78 ms on one thread, 1.7
//! times. Each half's arithmetic is the same whichever thread works it, so the results
//! are the same bits on one thread or two.

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Mutex, OnceLock, PoisonError};
use std::thread::Thread;
use std::time::{Duration, Instant};

/// One pass over a half of the blocks (see `solver::iterative`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Phase {
    /// The scaled system's right-hand side L^-1 F and start L^T x (D = L L^T the
    /// diagonal blocks).
    Scale,
    /// r = L^-1 F - (L^-1 K L^-T) x, the scaled system's residual; the sum is r . r.
    Residual,
    /// The bound's B = (L r)^T K_o^-1 (L r), the sum.
    Bound,
    /// p = r (a restart, `None`) or p = r + beta p.
    Turn(Option<f64>),
    /// q = (L^-1 K L^-T) p; the sum is p . q.
    Product,
    /// x += alpha p, r -= alpha q; the sum is r . r.
    Descend(f64),
    /// The solution x = L^-T x of the scaled system's.
    Unscale,
}

/// The second half's work: whichever thread claims a phase runs it.
type Second<'a> = Mutex<&'a mut (dyn FnMut(Phase) -> f64 + Send)>;

/// The two halves of a solve, on one thread or two.
pub(super) enum Team<'a> {
    /// The stepping thread works both halves, the first then the second.
    Alone(&'a mut (dyn FnMut(Phase) -> f64 + Send)),
    /// A helper thread works the second half, unless the stepping thread, done with the
    /// first, finds it not yet taken up and works it itself.
    Pair(&'a Link, &'a Second<'a>),
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
            Team::Pair(link, second) => {
                let k = link.post(phase);
                let s0 = first(phase);
                let s1 = if link.claim(k) {
                    work(second, phase)
                } else {
                    link.wait(k)
                };
                s0 + s1
            }
        }
    }
}

/// Runs `phase` by the second half's work.
fn work(second: &Second, phase: Phase) -> f64 {
    (second.lock().unwrap_or_else(PoisonError::into_inner))(phase)
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
    let second: Second = Mutex::new(&mut second);
    let link = Link::default();
    let stepping = std::thread::current();
    let _ = link.stepping.set(stepping.clone());
    std::thread::scope(|s| {
        let helper = s.spawn(|| {
            // Marks the helper gone however it ends, so that the stepping thread never
            // waits for it in vain.
            let _gone = Flag(&link.gone, Some(stepping));
            let mut seen = 0;
            while let Some((k, phase)) = link.next(&mut seen) {
                if link.claim(k) {
                    let sum = work(&second, phase);
                    link.finish(k, sum);
                }
            }
        });
        let _ = link.helper.set(helper.thread().clone());
        // Closes the link however `body` ends (a panic included), so that the helper
        // stops and the scope can end.
        let _close = Flag(&link.closed, Some(helper.thread().clone()));
        body(&mut Team::Pair(&link, &second))
    })
}

/// Runs `second` and `first`: `second` on a thread of its own when `threads` is set and
/// the thread pool has two threads or more, else one after the other on this thread.
pub(super) fn both(threads: bool, second: impl FnOnce() + Send, first: impl FnOnce()) {
    if !(threads && pool_threads() >= 2) {
        first();
        second();
        return;
    }
    std::thread::scope(|s| {
        s.spawn(second);
        first();
    });
}

/// Threads of the pool the solve runs in.
fn pool_threads() -> usize {
    #[cfg(feature = "rayon")]
    return rayon::current_num_threads();
    #[cfg(not(feature = "rayon"))]
    1
}

/// What the stepping thread and the helper share: the last phase posted and its number,
/// how many were posted, claimed and done, the last one's sum, whether either side has
/// ended, and both threads (to wake one that waits parked).
#[derive(Default)]
pub(super) struct Link {
    phase: Mutex<(u64, Option<Phase>)>,
    posted: AtomicU64,
    claimed: AtomicU64,
    done: AtomicU64,
    result: AtomicU64,
    closed: AtomicBool,
    gone: AtomicBool,
    helper: OnceLock<Thread>,
    stepping: OnceLock<Thread>,
}

impl Link {
    /// Posts `phase` to the helper; returns its number.
    fn post(&self, phase: Phase) -> u64 {
        let k = self.posted.load(Ordering::Relaxed) + 1;
        *self.phase.lock().unwrap_or_else(PoisonError::into_inner) = (k, Some(phase));
        self.posted.store(k, Ordering::Release);
        if let Some(helper) = self.helper.get() {
            helper.unpark();
        }
        k
    }

    /// Claims phase `k`'s second half for the calling thread: true for the first of the
    /// two threads to ask.
    fn claim(&self, k: u64) -> bool {
        self.claimed
            .compare_exchange(k - 1, k, Ordering::AcqRel, Ordering::Acquire)
            .is_ok()
    }

    /// The helper's side: phase `k`'s second half is done with sum `sum`.
    fn finish(&self, k: u64, sum: f64) {
        self.result.store(sum.to_bits(), Ordering::Relaxed);
        self.done.store(k, Ordering::Release);
        if let Some(t) = self.stepping.get() {
            t.unpark();
        }
    }

    /// Waits for the helper to finish phase `k`, which it claimed; returns its sum.
    fn wait(&self, k: u64) -> f64 {
        wait_until(|| self.done.load(Ordering::Acquire) == k || self.gone.load(Ordering::Acquire));
        if self.done.load(Ordering::Acquire) != k {
            panic!("the iterative solve's helper thread ended before its half was done");
        }
        f64::from_bits(self.result.load(Ordering::Relaxed))
    }

    /// The helper's side: waits for a phase after the `seen`-th and returns it with its
    /// number (now seen), or None once the link is closed.
    fn next(&self, seen: &mut u64) -> Option<(u64, Phase)> {
        wait_until(|| {
            self.posted.load(Ordering::Acquire) > *seen || self.closed.load(Ordering::Acquire)
        });
        let (k, phase) = *self.phase.lock().unwrap_or_else(PoisonError::into_inner);
        if k == *seen {
            return None;
        }
        *seen = k;
        phase.map(|p| (k, p))
    }
}

/// Sets its flag when dropped, and wakes the thread that may wait for it.
struct Flag<'a>(&'a AtomicBool, Option<Thread>);

impl Drop for Flag<'_> {
    fn drop(&mut self) {
        self.0.store(true, Ordering::Release);
        if let Some(t) = &self.1 {
            t.unpark();
        }
    }
}

/// How long a side spins for the other before it parks. A pass of a large system takes
/// tens of microseconds to milliseconds and the two halves end close together, so the
/// side that waits mostly finds the other done within this. Where more threads run than
/// there are cores (two runs at once on two cores) the helper may not be running at
/// all: then it parks, and the stepping thread works a phase's second half itself when
/// it finds it not taken up (`Link::claim`). Our choice, measured with two runs of the
/// 10,131-block column at once on two cores (20 steps each): spinning alone took their
/// solves 9.6 s each, spinning then parking 6.4 s, and with the second half claimed by
/// whichever thread comes first 5.5 s, against 4.4 s when the pool's workers took every
/// pass; alone, 0.45 ms a CG iteration against 0.56 ms. The helper spinning 5
/// microseconds instead: 5.1 s at once, 0.49 ms alone.
const SPIN: Duration = Duration::from_micros(50);

/// Waits until `ready`: spinning for [`SPIN`], then parked until woken (the other side
/// unparks this thread after each change it makes; a wake-up without one is checked and
/// waited out again).
fn wait_until(ready: impl Fn() -> bool) {
    let start = Instant::now();
    let mut tries = 0u32;
    while !ready() {
        tries += 1;
        if !tries.is_multiple_of(64) || start.elapsed() < SPIN {
            std::hint::spin_loop();
        } else {
            std::thread::park_timeout(Duration::from_millis(1));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::tests::in_pool_of_two;
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
        let two = in_pool_of_two(|| {
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
        assert_eq!(two, want);
        assert_eq!(sums(false), want);
    }
}
