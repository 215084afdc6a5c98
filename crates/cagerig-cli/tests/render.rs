//! End-to-end tests of `cagerig render` and of the demo's pictures, on the machine's adapter
//! (lavapipe / llvmpipe in CI), and of the path where no adapter exists.
//!
//! The picture tests need a Vulkan or GL adapter (software ones are fine); set
//! `CAGERIG_SKIP_GPU_TESTS=1` to skip them on a machine without one.

#![expect(clippy::unwrap_used)] // tests, benches and examples may panic on a broken fixture

#[expect(
    dead_code,
    reason = "each test binary uses a part of the shared helpers"
)]
mod support;

use std::path::Path;
use std::process::Output;
use support::{arm_dir, cagerig, temp_dir};

fn gpu_tests() -> bool {
    std::env::var_os("CAGERIG_SKIP_GPU_TESTS").is_none()
}

fn run(args: &[&str]) -> Output {
    let out = cagerig().args(args).output().unwrap();
    assert!(
        out.status.success(),
        "cagerig {args:?} failed:\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

/// Decodes a PNG: (width, height, RGBA bytes).
fn decode(path: &Path) -> (u32, u32, Vec<u8>) {
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).unwrap()));
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    buf.truncate(info.buffer_size());
    (info.width, info.height, buf)
}

/// Pixels of the columns `x0..x1` that are not the backdrop (bluish grey: blue above red) —
/// the skin is warm, the cage orange, the skeleton strongly blue.
fn content_pixels(image: &(u32, u32, Vec<u8>), x0: u32, x1: u32) -> usize {
    let (w, h, px) = image;
    let mut n = 0;
    for y in 0..*h {
        for x in x0..x1 {
            let i = ((y * w + x) * 4) as usize;
            let (r, g, b) = (px[i] as i32, px[i + 1] as i32, px[i + 2] as i32);
            let backdrop = b >= r && b - r < 30 && g > 150;
            n += usize::from(!backdrop);
        }
    }
    n
}

#[test]
fn the_f32_display_path_draws_the_same_picture() {
    if !gpu_tests() {
        return;
    }
    let dir = temp_dir("display_f32");
    let script = dir.join("edits.json");
    std::fs::write(
        &script,
        r#"{"skinning":"dqs","steps":[{"op":"rotate_joint","joint":3,"axis":[1,0,0],"degrees":50},
            {"op":"move_rest_cage","vertices":[0,2,4],"offset":[0.1,-0.05,0.1]}]}"#,
    )
    .unwrap();
    let mut pictures = Vec::new();
    for (name, extra) in [("exact.png", None), ("f32.png", Some("--display-f32"))] {
        let out = dir.join(name);
        let mut args = vec![
            "render",
            "--builtin",
            "snake",
            "--script",
            script.to_str().unwrap(),
            "--size",
            "320x240",
            "--out",
            out.to_str().unwrap(),
        ];
        args.extend(extra);
        run(&args);
        pictures.push(decode(&out));
    }
    let (a, b) = (&pictures[0].2, &pictures[1].2);
    assert_eq!(a.len(), b.len());
    let differing = a
        .chunks_exact(4)
        .zip(b.chunks_exact(4))
        .filter(|(p, q)| p.iter().zip(q.iter()).any(|(x, y)| x.abs_diff(*y) > 2))
        .count();
    assert!(
        differing * 1000 <= a.len() / 4,
        "{differing} pixels differ by more than 2 levels"
    );
}

#[test]
fn both_views_are_drawn_side_by_side_at_the_requested_size() {
    if !gpu_tests() {
        return;
    }
    let dir = temp_dir("both");
    let out = dir.join("bar.png");
    run(&[
        "render",
        "--builtin",
        "bar",
        "--view",
        "both",
        "--size",
        "400x200",
        "--out",
        out.to_str().unwrap(),
    ]);
    let image = decode(&out);
    assert_eq!((image.0, image.1), (400, 200));
    let left = content_pixels(&image, 0, 196);
    let right = content_pixels(&image, 204, 400);
    assert!(
        left > 2000 && right > 2000,
        "both views drawn: {left} / {right} content pixels"
    );
}

#[test]
fn arm_edit_script_colour_map_and_animation_times_render() {
    if !gpu_tests() {
        return;
    }
    let dir = temp_dir("arm");
    let script = dir.join("edits.json");
    std::fs::write(
        &script,
        r#"{"steps":[{"op":"rotate_joint","joint":"lowerarm01.R","axis":[1,0,0],"degrees":60},
                     {"op":"move_posed_cage","vertices":[20,23,25],"offset":[-1.5,2,0.5]}]}"#,
    )
    .unwrap();
    let arm = arm_dir();
    let mesh = arm.join("arm.obj");
    let out = dir.join("arm.png");
    run(&[
        "render",
        mesh.to_str().unwrap(),
        "--script",
        script.to_str().unwrap(),
        "--size",
        "320x240",
        "--color-by",
        "joint:lowerarm01.R",
        "--camera",
        "side",
        "--out",
        out.to_str().unwrap(),
    ]);
    let image = decode(&out);
    assert_eq!((image.0, image.1), (320, 240));
    assert!(content_pixels(&image, 0, 320) > 1000);

    let anim = dir.join("anim");
    let stdout = run(&[
        "render",
        mesh.to_str().unwrap(),
        "--skeleton-anim",
        arm.join("arm_skelAnim.txt").to_str().unwrap(),
        "--cage-anim",
        arm.join("arm_cageAnim.txt").to_str().unwrap(),
        "--times",
        "0.75,2.25",
        "--size",
        "160x120",
        "--out",
        anim.to_str().unwrap(),
    ])
    .stdout;
    let listed = String::from_utf8(stdout).unwrap();
    for t in ["0.75", "2.25"] {
        let path = anim.join(format!("t{t}.png"));
        assert!(path.is_file(), "{}", path.display());
        assert!(listed.contains(path.to_str().unwrap()), "{listed}");
    }
    // Several pictures are one output folder: a `.png` name is refused before anything is
    // drawn, and a non-empty folder is replaced only with --force.
    let refused = cagerig()
        .args(["render", mesh.to_str().unwrap(), "--times", "0,1"])
        .args([
            "--skeleton-anim",
            arm.join("arm_skelAnim.txt").to_str().unwrap(),
        ])
        .arg("--out")
        .arg(dir.join("anim.png"))
        .output()
        .unwrap();
    let said = String::from_utf8_lossy(&refused.stderr);
    assert!(!refused.status.success());
    assert!(
        said.contains("--times with 2 times writes a folder of pictures")
            && said.contains("expected a folder name"),
        "{said}"
    );
    assert!(!dir.join("anim.png").exists());
}

#[test]
fn turntable_writes_frames_and_an_animated_png() {
    if !gpu_tests() {
        return;
    }
    let dir = temp_dir("turntable");
    let out = dir.join("spin");
    let spin = |frames: &str, force: bool| {
        let mut c = cagerig();
        c.args(["render", "--builtin", "bar", "--turntable", frames])
            .args(["--size", "96x64", "--out", out.to_str().unwrap()]);
        if force {
            c.arg("--force");
        }
        c.output().unwrap()
    };
    assert!(spin("3", false).status.success());
    let mut names: Vec<String> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(
        names,
        [
            ".cagerig-output",
            "frame_000.png",
            "frame_001.png",
            "frame_002.png",
            "turntable.png"
        ]
    );
    let animated = out.join("turntable.png");
    let decoder = png::Decoder::new(std::io::BufReader::new(
        std::fs::File::open(&animated).unwrap(),
    ));
    let reader = decoder.read_info().unwrap();
    assert_eq!(reader.info().animation_control().unwrap().num_frames, 3);
    // An earlier output is replaced with --force only, and then wholly (no frame_002 left).
    let again = spin("2", false);
    assert!(!again.status.success());
    assert!(
        String::from_utf8_lossy(&again.stderr).contains("give --force"),
        "{}",
        String::from_utf8_lossy(&again.stderr)
    );
    assert!(spin("2", true).status.success());
    assert!(out.join("frame_001.png").is_file() && !out.join("frame_002.png").exists());
}

#[test]
fn demo_prints_where_its_pictures_are() {
    if !gpu_tests() {
        return;
    }
    let dir = temp_dir("demo");
    let stdout = String::from_utf8(run(&["demo", "--out", dir.to_str().unwrap()]).stdout).unwrap();
    for step in ["0_loaded", "1_bend", "2_inflate", "3_grab", "sequence"] {
        let path = dir.join(format!("{step}.png"));
        assert!(path.is_file(), "{}", path.display());
        assert!(stdout.contains(path.to_str().unwrap()), "{stdout}");
    }
}

#[test]
fn bad_options_fail_with_what_was_expected() {
    let dir = temp_dir("bad");
    let out = dir.join("x.png");
    let cases: [(&[&str], &str); 5] = [
        (&["--size", "12"], "WIDTHxHEIGHT"),
        (&["--show", "mesh,hair"], "unknown layer \"hair\""),
        (&["--camera", "behind"], "front, side, top, three-quarter"),
        (&["--color-by", "joint:nope"], "no joint named \"nope\""),
        (
            &["--color-by", "cage-vertex:999"],
            "cage vertex 999 does not exist",
        ),
    ];
    for (extra, expected) in cases {
        let mut args = vec!["render", "--builtin", "bar", "--out", out.to_str().unwrap()];
        args.extend_from_slice(extra);
        let result = cagerig().args(&args).output().unwrap();
        let stderr = String::from_utf8_lossy(&result.stderr);
        assert!(!result.status.success(), "{args:?} should fail");
        assert!(stderr.contains(expected), "{args:?}: {stderr}");
        assert!(!stderr.contains("panicked"), "{stderr}");
    }
    assert!(!out.exists());
}

#[test]
fn without_an_adapter_render_says_what_to_install_and_demo_still_works() {
    // DX12 does not exist on Linux (nor is it compiled in there): no adapter at all.
    let dir = temp_dir("noadapter");
    let out = dir.join("x.png");
    let result = cagerig()
        .args(["render", "--builtin", "bar", "--out", out.to_str().unwrap()])
        .env("WGPU_BACKEND", "dx12")
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&result.stderr);
    assert_eq!(result.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("no graphics adapter found"), "{stderr}");
    assert!(stderr.contains("mesa-vulkan-drivers"), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert!(!out.exists());

    let demo = dir.join("demo");
    let result = cagerig()
        .args(["demo", "--out", demo.to_str().unwrap()])
        .env("WGPU_BACKEND", "dx12")
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&result.stdout);
    assert!(
        result.status.success(),
        "{}",
        String::from_utf8_lossy(&result.stderr)
    );
    assert!(stdout.contains("warning: no pictures"), "{stdout}");
    assert!(demo.join("3_grab_mesh_posed.obj").is_file());
    assert!(!demo.join("3_grab.png").exists());
}

#[test]
fn edit_and_animate_render_a_picture_per_state_and_force_replaces_them() {
    if !gpu_tests() {
        return;
    }
    let dir = temp_dir("steps");
    let script = dir.join("edits.json");
    std::fs::write(
        &script,
        r#"{"steps":[{"op":"rotate_joint","joint":2,"axis":[0,0,1],"degrees":45}]}"#,
    )
    .unwrap();
    let out = dir.join("out");
    let args = [
        "edit",
        "--builtin",
        "bar",
        "--script",
        script.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--render",
    ];
    run(&args);
    for k in 0..=1 {
        let image = decode(&out.join(format!("step{k}.png")));
        assert!(content_pixels(&image, 0, image.0) > 2000);
    }
    // A second run with --force replaces the folder, pictures included.
    let mut forced = args.to_vec();
    forced.push("--force");
    run(&forced);
    assert!(out.join("step1.png").is_file());

    let arm = arm_dir();
    let anim = dir.join("anim");
    run(&[
        "animate",
        arm.join("arm.obj").to_str().unwrap(),
        "--skeleton-anim",
        arm.join("arm_skelAnim.txt").to_str().unwrap(),
        "--times",
        "0.75",
        "--out",
        anim.to_str().unwrap(),
        "--render",
    ]);
    assert!(anim.join("t0.75.png").is_file());
}

#[test]
fn a_gltf_character_renders_at_an_animation_time() {
    if !gpu_tests() {
        return;
    }
    let dir = temp_dir("fox");
    let fox = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../data/fox");
    let out = dir.join("fox.png");
    run(&[
        "render",
        fox.join("Fox.glb").to_str().unwrap(),
        "--cage",
        fox.join("Fox_cage.obj").to_str().unwrap(),
        "--animation",
        "Walk",
        "--times",
        "0.5",
        "--size",
        "200x150",
        "--out",
        out.to_str().unwrap(),
    ]);
    let image = decode(&out);
    assert!(content_pixels(&image, 0, 200) > 1000);
}
