//! A display backend from outside the library, written as `docs/architecture.md` ("A display
//! backend") says: this test crate implements `DisplayRestMapBackend` and
//! `DisplayRestMapProduct` the way a GPU backend would (coordinates uploaded once as f32, sums in
//! f32), passes it in `SessionOptions::display_rest_map`, and checks that the session draws its
//! rest skin with it, within the display path's 2e-6 of the diagonal, while the rig's state stays
//! bit-identical to a session on the CPU backend. A backend that cannot hold the coordinates
//! leaves the session on the exact product.

#![expect(clippy::unwrap_used)] // tests may panic on a broken fixture

use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};

use cagerig::cage_coords::CageCoords;
use cagerig::demo;
use cagerig::session::{
    DisplayPrecision, DisplayRestMap, DisplayRestMapBackend, DisplayRestMapProduct, RigParts,
    RigSession, SessionOptions,
};
use cagerig::{CoordsKind, RigError};
use glam::{DVec3, Vec3};

/// What the toy backend was asked to do.
#[derive(Debug, Default)]
struct Calls {
    uploads: AtomicUsize,
    applies: AtomicUsize,
}

/// The toy backend: holds the coordinates as one f32 matrix, row-major (`#V × #K`), as a GPU
/// storage buffer would, or refuses them all (`capacity` 0).
struct RowMajorF32 {
    calls: Arc<Calls>,
    capacity: usize,
}

#[derive(Debug)]
struct RowMajorProduct {
    calls: Arc<Calls>,
    rows: Vec<f32>,
    columns: usize,
}

impl DisplayRestMapBackend for RowMajorF32 {
    fn name(&self) -> &str {
        "toy row-major f32"
    }

    fn upload(&self, parts: &[&CageCoords]) -> Option<Arc<dyn DisplayRestMapProduct>> {
        self.calls.uploads.fetch_add(1, Ordering::Relaxed);
        let nv = parts.first()?.num_vertices();
        let columns: usize = parts.iter().map(|p| p.num_cage_vertices()).sum();
        if nv * columns > self.capacity {
            return None;
        }
        let mut rows = vec![0.0f32; nv * columns];
        let mut first = 0;
        for part in parts {
            for k in 0..part.num_cage_vertices() {
                for (i, &w) in part.column(k).iter().enumerate() {
                    rows[i * columns + first + k] = w as f32;
                }
            }
            first += part.num_cage_vertices();
        }
        Some(Arc::new(RowMajorProduct {
            calls: Arc::clone(&self.calls),
            rows,
            columns,
        }))
    }
}

impl DisplayRestMapProduct for RowMajorProduct {
    fn apply(&self, head: &[DVec3], tail: &[DVec3], out: &mut [Vec3]) {
        self.calls.applies.fetch_add(1, Ordering::Relaxed);
        assert_eq!(head.len() + tail.len(), self.columns);
        for (row, o) in self.rows.chunks_exact(self.columns).zip(out.iter_mut()) {
            *o = row
                .iter()
                .zip(head.iter().chain(tail))
                .fold(Vec3::ZERO, |sum, (&w, p)| sum + w * p.as_vec3());
        }
    }
}

fn session(coords: CoordsKind, display_rest_map: DisplayRestMap) -> RigSession {
    let rig = demo::builtin("snake", None).unwrap();
    let parts = RigParts::new(rig.mesh, rig.skeleton, rig.skin_weights, rig.cage);
    let options = SessionOptions {
        coords,
        display_rest_map,
        ..SessionOptions::default()
    };
    let mut session = RigSession::new(parts, options).unwrap().0;
    session
        .set_display_precision(DisplayPrecision::F32)
        .unwrap();
    session
}

/// Bends the snake, then grabs two current-cage vertices: the event that draws M̃.
fn bend_and_grab(session: &mut RigSession) -> Result<(), RigError> {
    session.rotate_joint(3, DVec3::new(0.3, 1.0, 0.2).normalize(), 0.1)?;
    session.move_posed_cage(&[9, 10], &[DVec3::new(0.002, -0.001, 0.0015)])
}

fn max_distance(shown: &[Vec3], exact: &[DVec3]) -> f64 {
    shown
        .iter()
        .zip(exact)
        .map(|(a, b)| a.as_dvec3().distance(*b))
        .fold(0.0, f64::max)
}

#[test]
fn an_external_backend_draws_the_rest_skin_and_leaves_the_rig_exact() {
    for coords in CoordsKind::ALL {
        let calls = Arc::new(Calls::default());
        let toy = DisplayRestMap::External(Arc::new(RowMajorF32 {
            calls: Arc::clone(&calls),
            capacity: usize::MAX,
        }));
        assert_eq!(toy.name(), "toy row-major f32");
        let mut external = session(coords, toy);
        let mut cpu = session(coords, DisplayRestMap::Cpu);
        bend_and_grab(&mut external).unwrap();
        bend_and_grab(&mut cpu).unwrap();
        assert_eq!(calls.uploads.load(Ordering::Relaxed), 1, "{coords:?}");
        assert_eq!(calls.applies.load(Ordering::Relaxed), 1, "{coords:?}");
        // The rig's state is the CPU backend's, bit for bit.
        assert_eq!(external.posed_cage(), cpu.posed_cage(), "{coords:?} C'");
        assert_eq!(external.rest_cage(), cpu.rest_cage(), "{coords:?} C");
        assert_eq!(external.posed_mesh(), cpu.posed_mesh(), "{coords:?} M'");
        // What is drawn comes from the toy, within the display path's bound.
        let exact = external.rest_mesh().to_vec();
        let lo = exact.iter().fold(DVec3::INFINITY, |a, &p| a.min(p));
        let hi = exact.iter().fold(DVec3::NEG_INFINITY, |a, &p| a.max(p));
        let shown = external
            .display_rest_mesh()
            .expect("the display path is on");
        let error = max_distance(shown, &exact);
        assert!(
            error <= 2e-6 * (hi - lo).length(),
            "{coords:?}: drawn M {error:e} from the exact one"
        );
    }
}

#[test]
fn a_backend_that_cannot_hold_the_coordinates_leaves_the_exact_product() {
    let calls = Arc::new(Calls::default());
    let full = DisplayRestMap::External(Arc::new(RowMajorF32 {
        calls: Arc::clone(&calls),
        capacity: 0,
    }));
    let mut session = session(CoordsKind::Mvc, full);
    bend_and_grab(&mut session).unwrap();
    assert_eq!(calls.uploads.load(Ordering::Relaxed), 1);
    assert_eq!(calls.applies.load(Ordering::Relaxed), 0);
    // The drawn M is the exact one rounded.
    let exact = session.rest_mesh().to_vec();
    let shown = session.display_rest_mesh().expect("the display path is on");
    for (a, b) in shown.iter().zip(&exact) {
        assert_eq!(*a, b.as_vec3());
    }
}
