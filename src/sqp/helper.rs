//! A second thread for the interior-point solver's short parallel
//! sections: the two halves of a supernodal factorisation (milliseconds)
//! and of a triangular solve (a tenth of a millisecond). A scoped thread
//! costs about 45 µs to start and join, and rayon's `in_place_scope` about
//! as much on these machines; this thread is started once per solver and
//! waits for work by spinning for a while ([`SPIN`]), then parks, so that
//! a hand-over between the solver's many sections costs about a
//! microsecond, and the thread sleeps while the SQP is elsewhere.

use std::cell::UnsafeCell;
use std::panic::{catch_unwind, resume_unwind, AssertUnwindSafe};
use std::sync::atomic::{AtomicBool, AtomicU8, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// How long the helper spins for its next job before it parks.
const SPIN: Duration = Duration::from_micros(200);

const IDLE: u8 = 0;
const POSTED: u8 = 1;
const DONE: u8 = 2;
const QUIT: u8 = 3;

/// The job handed over: a closure of the owner's stack, its lifetime
/// erased (see [`Helper::join`]).
type Job = *mut (dyn FnMut() + Send);

struct Shared {
    state: AtomicU8,
    job: UnsafeCell<Option<Job>>,
    panicked: AtomicBool,
}

// SAFETY: `job` is written by the owner only while the state is IDLE, and
// read by the helper only after it has seen POSTED (Acquire, pairing the
// owner's Release store); the owner reads the state DONE (Acquire,
// pairing the helper's Release) before it touches the job's closure again.
unsafe impl Sync for Shared {}
// SAFETY: as for Sync; the job pointer is only dereferenced by the helper
// between POSTED and DONE, while the owner keeps the closure alive.
unsafe impl Send for Shared {}

pub(crate) struct Helper {
    shared: Arc<Shared>,
    thread: Option<JoinHandle<()>>,
}

impl Helper {
    /// Start the helper thread, or None where the system refuses a
    /// thread (the caller then runs both halves itself).
    pub(crate) fn new() -> Option<Helper> {
        let shared = Arc::new(Shared {
            state: AtomicU8::new(IDLE),
            job: UnsafeCell::new(None),
            panicked: AtomicBool::new(false),
        });
        let theirs = Arc::clone(&shared);
        let thread = std::thread::Builder::new()
            .name("leap-kkt".into())
            .spawn(move || serve(&theirs))
            .ok()?;
        Some(Helper {
            shared,
            thread: Some(thread),
        })
    }

    /// Run `theirs` on the helper thread and `ours` on this one; return
    /// `ours`' result and whether `theirs` returned (false: it panicked,
    /// a bug, which the caller reports as a failure instead of crashing).
    pub(crate) fn join<R>(
        &mut self,
        theirs: &mut (dyn FnMut() + Send),
        ours: impl FnOnce() -> R,
    ) -> (R, bool) {
        let s = &*self.shared;
        // SAFETY: the lifetime of `theirs` is erased for the hand-over;
        // this function does not return (nor unwind) before the helper has
        // reported DONE, after which it no longer touches the closure.
        let job: Job = unsafe {
            std::mem::transmute::<&mut (dyn FnMut() + Send), &'static mut (dyn FnMut() + Send)>(
                theirs,
            )
        };
        // SAFETY: the state is IDLE (every join waits for DONE and resets
        // it), so the helper does not read `job` now.
        unsafe { *s.job.get() = Some(job) };
        s.state.store(POSTED, Ordering::Release);
        if let Some(t) = &self.thread {
            t.thread().unpark();
        }
        let result = catch_unwind(AssertUnwindSafe(ours));
        let mut spins = 0u32;
        while s.state.load(Ordering::Acquire) != DONE {
            spins = spins.wrapping_add(1);
            if spins.is_multiple_of(1024) {
                std::thread::yield_now();
            } else {
                std::hint::spin_loop();
            }
        }
        // SAFETY: the helper is done with the job (DONE seen with Acquire).
        unsafe { *s.job.get() = None };
        s.state.store(IDLE, Ordering::Relaxed);
        let ok = !s.panicked.swap(false, Ordering::Relaxed);
        match result {
            Ok(r) => (r, ok),
            Err(payload) => resume_unwind(payload),
        }
    }
}

impl Drop for Helper {
    fn drop(&mut self) {
        self.shared.state.store(QUIT, Ordering::Release);
        if let Some(t) = self.thread.take() {
            t.thread().unpark();
            // The helper catches its jobs' panics: its loop returns.
            let _ = t.join();
        }
    }
}

/// The helper's loop: wait for a job (spinning, then parked), run it,
/// report DONE; return on QUIT.
fn serve(s: &Shared) {
    let mut idle_since = Instant::now();
    let mut spins = 0u32;
    loop {
        match s.state.load(Ordering::Acquire) {
            POSTED => {
                // SAFETY: POSTED was stored (Release) after the job.
                let job = unsafe { *s.job.get() };
                if let Some(job) = job {
                    // SAFETY: the owner keeps the closure alive and
                    // untouched until it sees DONE.
                    let f = unsafe { &mut *job };
                    if catch_unwind(AssertUnwindSafe(f)).is_err() {
                        s.panicked.store(true, Ordering::Relaxed);
                    }
                }
                s.state.store(DONE, Ordering::Release);
                idle_since = Instant::now();
            }
            QUIT => return,
            _ => {
                spins = spins.wrapping_add(1);
                // The clock is read every 64th turn only.
                if !spins.is_multiple_of(64) || idle_since.elapsed() < SPIN {
                    std::hint::spin_loop();
                } else {
                    // A spurious or early wake-up only loops again.
                    std::thread::park_timeout(Duration::from_millis(50));
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Both halves run, each on its own data, many times over; a panic of
    /// the helper's half is reported, and the helper serves on.
    #[test]
    fn halves_run_and_a_panic_is_reported() {
        let mut helper = Helper::new().unwrap();
        let (mut a, mut b) = (vec![0u64; 100], vec![0u64; 100]);
        for round in 0..2000u64 {
            let (r, ok) = helper.join(&mut || b.iter_mut().for_each(|x| *x += round), || {
                a.iter_mut().for_each(|x| *x += 2 * round);
                round
            });
            assert!(ok);
            assert_eq!(r, round);
            if round % 500 == 0 {
                // Long enough for the helper to park.
                std::thread::sleep(Duration::from_millis(2));
            }
        }
        let sum: u64 = (0..2000).sum();
        assert!(a.iter().all(|&x| x == 2 * sum));
        assert!(b.iter().all(|&x| x == sum));
        let (_, ok) = helper.join(&mut || panic!("a bug in the helper's half"), || ());
        assert!(!ok);
        let mut ran = false;
        let (_, ok) = helper.join(&mut || ran = true, || ());
        assert!(ok && ran);
    }
}
