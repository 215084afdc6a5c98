//! The printed report of `cagerig bench`: one table per model, each row with its median, min
//! and max on the default thread pool, the median on one thread, the bytes the kernel must move
//! and the bandwidth that implies (also as a share of the machine's read bandwidth, measured in
//! the same run), and — when the model is the paper's Arm at a size its tool was
//! measured on — the tool's single-threaded median and how many times faster each of ours is.

use crate::bench_report::{ModelReport, ModelRow, Stat};

/// The paper tool's medians in ms (single thread, -O3 -march=native, this project's machine
/// kind, as published with the paper tool's timings table) on the Arm (2,089 vertices) and its
/// 2× / 3× midpoint subdivisions (33,289 / 133,073), per bench row. `None`: the tool has no
/// such step (it loads MaxVol rows and CoR centres from files).
struct ToolFigures {
    mvc: [f64; 3],
    skelup_preprocess: [f64; 3],
    cageup_preprocess: [f64; 3],
    cagerev_refactor: [f64; 3],
    lbs: [f64; 3],
    dqs: [f64; 3],
    cor: [f64; 3],
    animation_frame: [f64; 3],
    rest_cage_drag: [f64; 3],
    grab_after_skeleton_edit: [f64; 3],
}

const TOOL: ToolFigures = ToolFigures {
    mvc: [22.8, 382.0, 2176.0],
    skelup_preprocess: [153.0, 1568.0, 5930.0],
    cageup_preprocess: [0.183, 0.183, 0.187],
    cagerev_refactor: [5.03, 9.3, 5.19],
    lbs: [0.109, 1.88, 22.9],
    dqs: [0.033, 0.614, 14.2],
    cor: [0.178, 8.5, 39.6],
    animation_frame: [0.430, 13.6, 65.9],
    rest_cage_drag: [0.439, 12.6, 56.5],
    grab_after_skeleton_edit: [5.69, 19.0, 62.7],
};

/// Which column of [`TOOL`] a model matches: the Arm (25 joints, 58 cage vertices) at 0, 2 or
/// 3 subdivision levels.
fn tool_column(row: &ModelRow) -> Option<usize> {
    if row.joints != 25 || row.cage_vertices != 58 {
        return None;
    }
    [2_089, 33_289, 133_073]
        .iter()
        .position(|&n| n == row.vertices)
}

fn ratio(tool_ms: Option<f64>, ours_ms: Option<f64>) -> String {
    match (tool_ms, ours_ms) {
        (Some(t), Some(o)) if o > 0.0 => format!("{:.1}×", t / o),
        _ => String::new(),
    }
}

/// `gbs` as a percentage of the read bandwidth `read_gbs` (empty when that is unknown).
fn share_of(gbs: f64, read_gbs: f64) -> String {
    if read_gbs > 0.0 && gbs.is_finite() {
        format!("{:.0} %", 100.0 * gbs / read_gbs)
    } else {
        String::new()
    }
}

/// Prints one table per model.
pub(crate) fn print_table(reports: &[ModelReport]) {
    for report in reports {
        let r = &report.row;
        let single = report.one_thread.as_ref();
        let column = tool_column(r);
        println!(
            "\n{}: {} vertices, {} joints, {} cage vertices, peak memory {:.0} MB, kernels in {}, \
             MaxVol ln|det| {:.4}, memory read bandwidth {:.1} GB/s{}",
            r.model,
            r.vertices,
            r.joints,
            r.cage_vertices,
            r.peak_memory_mb,
            r.precision,
            r.maxvol_log_abs_det,
            report.read_bandwidth_gbs,
            report
                .read_bandwidth_gbs_one_thread
                .map_or(String::new(), |gbs| format!(" ({gbs:.1} on 1 thread)"))
        );
        println!(
            "  {:<30} {:>10} {:>9} {:>9} {:>10} {:>11} {:>7} {:>6} {:>9} {:>8} {:>8}",
            "operation",
            "median ms",
            "min ms",
            "max ms",
            "1 thread",
            "bytes moved",
            "GB/s",
            "% read",
            "tool ms",
            "× tool",
            "× 1 thr"
        );
        let line = |name: &str, pick: &dyn Fn(&ModelRow) -> Stat, tool: Option<&[f64; 3]>| {
            let s = pick(r);
            let one = single.map(|row| pick(row).median_ms);
            let tool_ms = tool.zip(column).map(|(t, c)| t[c]);
            let (bytes, bw, share) = match s.bytes_moved {
                Some(b) => {
                    let gbs = b as f64 / 1e6 / s.median_ms;
                    (
                        format!("{:.1} MB", b as f64 / 1e6),
                        format!("{gbs:.1}"),
                        share_of(gbs, report.read_bandwidth_gbs),
                    )
                }
                None => (String::new(), String::new(), String::new()),
            };
            println!(
                "  {:<30} {:>10.3} {:>9.3} {:>9.3} {:>10} {:>11} {:>7} {:>6} {:>9} {:>8} {:>8}",
                name,
                s.median_ms,
                s.min_ms,
                s.max_ms,
                one.map_or(String::new(), |m| format!("{m:.3}")),
                bytes,
                bw,
                share,
                tool_ms.map_or(String::new(), |t| format!("{t}")),
                ratio(tool_ms, Some(s.median_ms)),
                ratio(tool_ms, one),
            );
        };
        line("MVC Φ (all vertices)", &|m| m.mvc, Some(&TOOL.mvc));
        line("MaxVol selection", &|m| m.maxvol, None);
        line(
            "SkelUp preprocess (Ψ)",
            &|m| m.skelup_preprocess,
            Some(&TOOL.skelup_preprocess),
        );
        line("binding (Φ + MaxVol + Ψ)", &binding, None);
        line(
            "CageUp preprocess",
            &|m| m.cageup_preprocess,
            Some(&TOOL.cageup_preprocess),
        );
        line(
            &format!("CoR centres ({})", r.cor_centres_method),
            &|m| m.cor_centres,
            None,
        );
        line(
            "CageRev refactor",
            &|m| m.cagerev_refactor,
            Some(&TOOL.cagerev_refactor),
        );
        line("LBS skinning", &|m| m.lbs, Some(&TOOL.lbs));
        line("DQS skinning", &|m| m.dqs, Some(&TOOL.dqs));
        line("CoR skinning", &|m| m.cor, Some(&TOOL.cor));
        line("LBS skinning (f32)", &|m| m.lbs_f32, Some(&TOOL.lbs));
        line("DQS skinning (f32)", &|m| m.dqs_f32, Some(&TOOL.dqs));
        line("CoR skinning (f32)", &|m| m.cor_f32, Some(&TOOL.cor));
        line(
            "animation frame (LBS)",
            &|m| m.animation_frame,
            Some(&TOOL.animation_frame),
        );
        line(
            "rest-cage drag, 5 v, sync",
            &|m| m.rest_cage_drag,
            Some(&TOOL.rest_cage_drag),
        );
        line(
            "grab after skeleton edit",
            &|m| m.grab_after_skeleton_edit,
            Some(&TOOL.grab_after_skeleton_edit),
        );
        line(
            "rest-cage drag (f32 Φ)",
            &|m| m.rest_cage_drag_f32_coords,
            Some(&TOOL.rest_cage_drag),
        );
        line(
            "grab after skel. edit (f32 Φ)",
            &|m| m.grab_after_skeleton_edit_f32_coords,
            Some(&TOOL.grab_after_skeleton_edit),
        );
        line(
            "rest-cage drag (display)",
            &|m| m.rest_cage_drag_display,
            Some(&TOOL.rest_cage_drag),
        );
        line(
            "grab after skel. edit (display)",
            &|m| m.grab_after_skeleton_edit_display,
            Some(&TOOL.grab_after_skeleton_edit),
        );
        match r.animation_cage_quality {
            Some(q) => println!(
                "  current cage along the animation ({} fit): {q}",
                r.cage_fit
            ),
            None => println!("  current cage along the animation: every frame refused"),
        }
    }
}

/// The whole binding of a character: Φ, the MaxVol rows and Ψ (sums of the three rows).
fn binding(m: &ModelRow) -> Stat {
    Stat {
        median_ms: m.mvc.median_ms + m.maxvol.median_ms + m.skelup_preprocess.median_ms,
        min_ms: m.mvc.min_ms + m.maxvol.min_ms + m.skelup_preprocess.min_ms,
        max_ms: m.mvc.max_ms + m.maxvol.max_ms + m.skelup_preprocess.max_ms,
        bytes_moved: None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ratios_and_tool_columns() {
        assert_eq!(ratio(Some(1.0), Some(0.25)), "4.0×");
        assert_eq!(ratio(None, Some(0.25)), "");
        assert_eq!(ratio(Some(1.0), None), "");
        assert_eq!(TOOL.dqs[0], 0.033);
        assert_eq!(share_of(36.0, 72.0), "50 %");
        assert_eq!(share_of(36.0, 0.0), "");
    }
}
