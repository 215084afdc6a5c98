//! Per-event work must not allocate: a counting global allocator checks the session's
//! skeleton edits, rest-cage drags, current-cage grabs (with a held factorisation), skinning
//! switches between already-built methods and cage grabs, on the exact and the f32 display path.
//!
//! The events run inside the rayon pool (as an interactive front end would): called from a
//! foreign thread, rayon's own injector queue allocates a block every few dozen jobs, which is
//! rayon's amortised bookkeeping, not per-event work of ours.

#![expect(
    unsafe_code,
    reason = "a counting global allocator wraps the system one"
)]
#![expect(clippy::unwrap_used)] // tests, benches and examples may panic on a broken fixture

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

use cagerig::demo;
use cagerig::session::{DisplayPrecision, RigParts, RigSession, SessionOptions};
use cagerig::skinning::SkinningMethod;
use glam::DVec3;

#[expect(
    dead_code,
    reason = "each test binary uses a part of the shared helpers"
)]
mod support;

struct Counting;

static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);

// SAFETY: every method forwards to the system allocator with the caller's arguments unchanged,
// so `System`'s guarantees are this allocator's; counting touches no allocated memory.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::SeqCst);
        // SAFETY: the caller upholds `GlobalAlloc::alloc`'s contract for `layout`.
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: `ptr` was allocated by `System` through this allocator with `layout`.
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::SeqCst);
        // SAFETY: as for `dealloc`, and the caller upholds `realloc`'s size contract.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

fn allocations_during(mut f: impl FnMut()) -> usize {
    let before = ALLOCATIONS.load(Ordering::SeqCst);
    f();
    ALLOCATIONS.load(Ordering::SeqCst) - before
}

#[test]
fn per_event_work_does_not_allocate() {
    let pool = rayon::ThreadPoolBuilder::new().build().unwrap();
    pool.install(run_events);
}

fn run_events() {
    // One test in this binary, so no other test thread allocates meanwhile.
    let rig = demo::builtin("snake", Some(20_000)).unwrap();
    let blend = support::spread_blend_weights(rig.mesh.num_vertices());
    let parts = RigParts::new(rig.mesh, rig.skeleton, rig.skin_weights, rig.cage)
        .with_dq_blend_weights(Some(blend));
    let (mut s, _) = RigSession::new(parts, SessionOptions::default()).unwrap();
    s.set_skinning(SkinningMethod::Cor).unwrap();
    s.set_skinning(SkinningMethod::Lbs).unwrap();
    let offset = DVec3::new(0.01, 0.02, -0.01);
    // Warm up (thread pool, work-stealing queues).
    for _ in 0..3 {
        s.rotate_joint(3, DVec3::Z, 0.01).unwrap();
        s.move_rest_cage(&[1, 2], &[offset]).unwrap();
        s.move_posed_cage(&[4], &[offset]).unwrap();
        s.move_posed_cage(&[4], &[-offset]).unwrap();
    }
    let n = allocations_during(|| {
        s.rotate_joint(5, DVec3::Y, 0.02).unwrap();
    });
    assert_eq!(n, 0, "rotate_joint allocated {n} times");
    for method in SkinningMethod::ALL {
        let n = allocations_during(|| s.set_skinning(method).unwrap());
        assert_eq!(n, 0, "set_skinning({method:?}) allocated {n} times");
        let n = allocations_during(|| s.move_rest_cage(&[0, 3, 7], &[offset]).unwrap());
        assert_eq!(n, 0, "move_rest_cage ({method:?}) allocated {n} times");
    }
    s.refactor_reverser().unwrap();
    let n = allocations_during(|| s.move_posed_cage(&[9, 10], &[offset]).unwrap());
    assert_eq!(n, 0, "move_posed_cage allocated {n} times");

    // The f32 display path: kernels are built on first use of each method, then events
    // allocate nothing either.
    s.set_display_precision(DisplayPrecision::F32).unwrap();
    for method in SkinningMethod::ALL {
        s.set_skinning(method).unwrap();
        s.move_rest_cage(&[0, 3, 7], &[offset]).unwrap();
        let n = allocations_during(|| s.rotate_joint(5, DVec3::Y, 0.02).unwrap());
        assert_eq!(
            n, 0,
            "display path: rotate_joint ({method:?}) allocated {n} times"
        );
        let n = allocations_during(|| s.move_rest_cage(&[0, 3, 7], &[offset]).unwrap());
        assert_eq!(
            n, 0,
            "display path: move_rest_cage ({method:?}) allocated {n} times"
        );
        // Φ̃ is built at the first grab; then a grab (M̃ and the exact MaxVol rows) and the
        // rest-cage edit after it (the whole exact M first) allocate nothing.
        s.move_posed_cage(&[4], &[offset]).unwrap();
        s.refactor_reverser().unwrap();
        let n = allocations_during(|| s.move_posed_cage(&[9, 10], &[offset]).unwrap());
        assert_eq!(
            n, 0,
            "display path: move_posed_cage ({method:?}) allocated {n} times"
        );
        let n = allocations_during(|| s.move_rest_cage(&[1], &[offset]).unwrap());
        assert_eq!(
            n, 0,
            "display path: move_rest_cage after a grab ({method:?}) allocated {n} times"
        );
    }
}
