//! The progress that the coordinates' parallel computations report.

use glam::DVec3;

use super::green::compute_green_coords;
use super::mvc::compute_cage_coords;
use crate::mesh::TriMesh;

/// The progress of both kinds of coordinates ends on the whole count, whatever order the worker
/// threads report in. A slower thread's earlier count could arrive last, which made a progress
/// bar stop short and the Blender add-on's test fail now and then; here every earlier count is
/// reported 1 ms late, so the report of the whole would overtake it.
#[test]
fn the_last_progress_report_is_every_point() {
    let cage = TriMesh::cuboid(DVec3::splat(-1.0), DVec3::ONE).unwrap();
    let points: Vec<DVec3> = (0..8192)
        .map(|i| {
            let t = i as f64 / 8192.0;
            DVec3::new(
                0.3 * (t * 17.0).sin(),
                0.3 * (t * 29.0).cos(),
                0.6 * t - 0.3,
            )
        })
        .collect();
    type Compute = fn(&TriMesh, &[DVec3], &(dyn Fn(usize) + Sync));
    let kinds: [(&str, Compute); 2] = [
        ("mean value", |cage, points, report| {
            compute_cage_coords(cage, points, Some(report)).unwrap();
        }),
        ("Green", |cage, points, report| {
            compute_green_coords(cage, points, Some(report)).unwrap();
        }),
    ];
    for (kind, compute) in kinds {
        for _ in 0..10 {
            let reports = std::sync::Mutex::new(Vec::new());
            let record = |done: usize| {
                if done < points.len() {
                    std::thread::sleep(std::time::Duration::from_millis(1));
                }
                reports.lock().unwrap().push(done);
            };
            compute(&cage, &points, &record);
            let reports = reports.into_inner().unwrap();
            assert_eq!(reports.last(), Some(&points.len()), "{kind}: {reports:?}");
            assert!(reports.iter().all(|&d| d <= points.len()), "{kind}");
            let whole = reports.iter().filter(|&&d| d == points.len()).count();
            assert_eq!(whole, 1, "{kind}: {reports:?}");
        }
    }
}
