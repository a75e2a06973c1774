//! The hot path (set the state, apply a point force, solve for q̈) allocates
//! nothing once the workspace exists.

use leap::model::Model;
use leap::multibody::Multibody;
use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

struct Counting;
static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);

thread_local! {
    /// Allocations are counted only on threads that ask (tests run in parallel).
    static COUNTING: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

fn counted<R>(f: impl FnOnce() -> R) -> (R, usize) {
    let before = ALLOCATIONS.load(Ordering::SeqCst);
    COUNTING.with(|c| c.set(true));
    let r = f();
    COUNTING.with(|c| c.set(false));
    (r, ALLOCATIONS.load(Ordering::SeqCst) - before)
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        if COUNTING.with(|c| c.get()) {
            ALLOCATIONS.fetch_add(1, Ordering::SeqCst);
        }
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

#[test]
fn forward_dynamics_allocates_nothing() {
    let m = Model::from_file("models/jumper_gait2392.json").unwrap();
    let sys = m.system(true).unwrap();
    let mb = Multibody::new(&m, &sys);
    let mut ws = mb.workspace::<f64>();
    let q = sys.q_from_model(&m.poses["squat"]);
    let u = vec![0.1; 7];
    let mut tau = vec![0.0; 7];
    let mut qdd = vec![0.0; 7];
    let (hb, hp) = mb.stations()[0];
    let (_, n) = counted(|| {
        for _ in 0..100 {
            mb.set_state(&mut ws, &q, &u);
            tau.iter_mut().for_each(|t| *t = 1.0);
            mb.add_point_force(&ws, hb, hp, [10.0, 700.0, 0.0], &mut tau);
            mb.forward_dynamics(&mut ws, &tau, &mut qdd).unwrap();
            std::hint::black_box(mb.com_acceleration(&ws, &qdd));
        }
    });
    assert_eq!(n, 0);
}

#[test]
fn state_equation_allocates_nothing() {
    let m = Model::from_file("models/jumper_gait2392.json").unwrap();
    let eq =
        leap::ode::StateEquation::new(&m, true, leap::path::PathSmoothing::Smooth { delta: 0.02 })
            .unwrap();
    let laws = leap::laws::OpenSimLaws::new(&m).unwrap();
    let sq = leap::squat::static_squat(&eq, &laws, &m.poses["squat"]).unwrap();
    let mut ws = eq.workspace::<f64>();
    let mut xd = vec![0.0; eq.nx()];
    eq.rhs(&laws, &mut ws, &sq.x, &sq.excitation, &mut xd)
        .unwrap();
    let (_, n) = counted(|| {
        for _ in 0..50 {
            eq.rhs(&laws, &mut ws, &sq.x, &sq.excitation, &mut xd)
                .unwrap();
        }
    });
    assert_eq!(n, 0);
}
