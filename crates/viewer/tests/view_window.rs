//! `lustre view` in a real window: under Xvfb with the installed Vulkan driver, the window plays a camera path, takes a screenshot and closes; the screenshot, and the window's own pixels, match `lustre render` of the path's last frame by FLIP. A per-vertex technique moves the mobile objects live with the quasi-static update: held at a time along their path, the window shows `lustre render --frames`' frame of that time.
//!
//! Needs `xvfb-run` (Debian's xvfb). Without it the test skips with a message, unless `LUSTRE_REQUIRE_GPU` is set (CI), where it fails.

mod support;

use std::path::{Path, PathBuf};
use std::process::Command;

use lustre_image::metrics::flip;
use lustre_image::{Image, read_exr};
use support::{render_or_skip, scratch, sidecar};

/// The render's size: small, so the window test stays short on the software driver.
const SIZE: (u32, u32) = (160, 120);

/// The camera path, from the workspace's tests.
fn walk() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/paths/glosbox-walk.json")
}

/// Whether `xvfb-run` is on the PATH; without it the test skips with a message, or fails under `LUSTRE_REQUIRE_GPU` (CI).
fn xvfb_or_skip() -> bool {
    let have = Command::new("sh")
        .args(["-c", "command -v xvfb-run"])
        .output()
        .is_ok_and(|o| o.status.success());
    if !have {
        assert!(
            std::env::var_os("LUSTRE_REQUIRE_GPU").is_none(),
            "LUSTRE_REQUIRE_GPU is set but xvfb-run is missing (apt-get install xvfb)"
        );
        eprintln!("SKIPPED the window test: no xvfb-run (apt-get install xvfb)");
    }
    have
}

/// An sRGB PNG's top-right `w` × `h` pixels (the window's image, right of the panel), decoded to linear radiance.
fn image_part_of_window(path: &Path, (w, h): (u32, u32)) -> Image {
    let window = image::open(path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .to_rgb8();
    assert!(
        window.width() >= w && window.height() >= h,
        "window {}x{} smaller than the image",
        window.width(),
        window.height()
    );
    let x0 = window.width() - w;
    let decode = |c: u8| {
        let v = f32::from(c) / 255.0;
        if v <= 0.04045 {
            v / 12.92
        } else {
            ((v + 0.055) / 1.055).powf(2.4)
        }
    };
    let pixels: Vec<[f32; 4]> = (0..h)
        .flat_map(|y| (0..w).map(move |x| (x, y)))
        .map(|(x, y)| {
            let p = window.get_pixel(x0 + x, y).0;
            [decode(p[0]), decode(p[1]), decode(p[2]), 1.0]
        })
        .collect();
    Image::from_rgba(w, h, &pixels).unwrap()
}

#[test]
fn the_window_plays_a_path_and_its_screenshot_matches_render() {
    if !xvfb_or_skip() {
        return;
    }
    let dir = scratch("view-window");
    let size = format!("{}x{}", SIZE.0, SIZE.1);
    let common = [
        "glosbox",
        "--size",
        &size,
        "--photons",
        "20000",
        "--aa",
        "2",
    ];
    // The render of the path's frames; its last is where the window's playback ends.
    let render_out = dir.join("render.exr");
    let mut render_args = vec!["render"];
    render_args.extend(common);
    let walk = walk();
    let walk = walk.to_str().unwrap();
    render_args.extend(["--camera-path", walk, "--path-frames", "3", "--out"]);
    render_args.push(render_out.to_str().unwrap());
    let Some(out) = render_or_skip("the window test", &render_args) else {
        return;
    };
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let rendered = read_exr(dir.join("render-0002.exr")).unwrap();

    let shot = dir.join("view.exr");
    let mut args = common.to_vec();
    args.extend(["--fixed-size", "--play", walk, "--play-frames", "3"]);
    args.extend(["--screenshot", shot.to_str().unwrap(), "--exit"]);
    let stderr = view_under_xvfb(&args);
    // Nothing on stderr but what the window reports.
    for line in stderr.lines() {
        assert!(
            ["window on ", "beams: ", "traced ", "wrote "]
                .iter()
                .any(|s| line.starts_with(s)),
            "unexpected stderr line {line:?} in:\n{stderr}"
        );
    }

    // The screenshot is the path's last frame, as render drew it.
    let info = sidecar(&shot);
    let camera = &info["camera"]["position"];
    let keyframes: serde_json::Value =
        serde_json::from_slice(&std::fs::read(walk).unwrap()).unwrap();
    let last = &keyframes["keyframes"].as_array().unwrap().last().unwrap()["position"];
    for i in 0..3 {
        let (a, b) = (camera[i].as_f64().unwrap(), last[i].as_f64().unwrap());
        assert!((a - b).abs() < 1e-4, "camera {camera} against {last}");
    }
    assert_eq!(info["photons"], 20000);
    let viewed = read_exr(&shot).unwrap();
    let same = flip(&viewed, &rendered, 0.0).unwrap();
    assert!(
        same.mean <= 0.01,
        "screenshot against render: FLIP mean {}",
        same.mean
    );
    // The PNG beside it, and the window's own pixels: what was shown.
    assert!(shot.with_extension("png").is_file());
    let window = image_part_of_window(&dir.join("view-window.png"), SIZE);
    let shown = flip(&window, &rendered, 0.0).unwrap();
    assert!(
        shown.mean <= 0.01,
        "the window's pixels against render: FLIP mean {}",
        shown.mean
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// Runs `lustre view ARGS` under Xvfb and returns its stderr; panics when it fails.
fn view_under_xvfb(args: &[&str]) -> String {
    let out = Command::new("timeout")
        .args(["600", "xvfb-run", "-a", "-s", "-screen 0 800x600x24"])
        .arg(env!("CARGO_BIN_EXE_lustre"))
        .arg("view")
        .args(args)
        .output()
        .expect("xvfb-run runs");
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(out.status.success(), "lustre view failed: {stderr}");
    stderr
}

#[test]
fn a_per_vertex_technique_moves_the_objects_with_the_quasi_static_update() {
    if !xvfb_or_skip() {
        return;
    }
    let dir = scratch("view-quasi-static");
    let size = format!("{}x{}", SIZE.0, SIZE.1);
    let common = [
        "cornell",
        "--technique",
        "detp",
        "--size",
        &size,
        "--photons",
        "20000",
    ];
    // cornell's small box loops every 8 s: --frames 2 draws it at 0 and 4 s.
    let render_out = dir.join("render.exr");
    let mut render_args = vec!["render"];
    render_args.extend(common);
    render_args.extend(["--frames", "2", "--out", render_out.to_str().unwrap()]);
    let Some(out) = render_or_skip("the quasi-static window test", &render_args) else {
        return;
    };
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let at_rest = read_exr(dir.join("render-0000.exr")).unwrap();
    let moved = read_exr(dir.join("render-0001.exr")).unwrap();

    // Held at 4 s: the window's quasi-static frame is render's second.
    let shot = dir.join("held.exr");
    let mut args = common.to_vec();
    args.extend(["--fixed-size", "--object-time", "4", "--screenshot"]);
    args.extend([shot.to_str().unwrap(), "--exit"]);
    view_under_xvfb(&args);
    let info = sidecar(&shot);
    assert_eq!(info["quasi_static"]["frame"], 1, "{info}");
    assert_eq!(info["quasi_static"]["object_seconds"], 4.0, "{info}");
    let viewed = read_exr(&shot).unwrap();
    let same = flip(&viewed, &moved, 0.0).unwrap();
    assert!(
        same.mean <= 0.01,
        "held at 4 s against render's frame at 4 s: FLIP mean {}",
        same.mean
    );
    let other = flip(&viewed, &at_rest, 0.0).unwrap();
    assert!(
        other.mean > 0.02,
        "the small box did not move: FLIP mean {} against the frame at 0 s",
        other.mean
    );

    // Moving with the clock while a short path plays (how many poses the
    // window shows before its screenshot depends on the machine; the
    // lighting module's unit test holds the poses to the clock).
    let shot = dir.join("moving.exr");
    let walk = walk();
    let mut args = common.to_vec();
    args.extend(["--fixed-size", "--play", walk.to_str().unwrap()]);
    args.extend(["--play-frames", "12", "--screenshot"]);
    args.extend([shot.to_str().unwrap(), "--exit"]);
    view_under_xvfb(&args);
    let info = sidecar(&shot);
    let frame = info["quasi_static"]["frame"].as_u64().unwrap();
    let seconds = info["quasi_static"]["object_seconds"].as_f64().unwrap();
    assert!(frame >= 1 && seconds >= 0.0, "{info}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn view_refuses_bad_input_before_opening_a_window() {
    for (args, expected) in [
        (
            vec!["view", "no-such-scene.obj"],
            "neither a built-in scene",
        ),
        (
            vec!["view", "glosbox", "--object-time", "2"],
            "--object-time: only the per-vertex techniques",
        ),
        (
            vec![
                "view",
                "cornell",
                "--technique",
                "detp",
                "--object-time",
                "NaN",
            ],
            "seconds must be finite",
        ),
        (
            vec!["view", "glosbox", "--screenshot", "shot.tiff"],
            "must end in .exr or .png",
        ),
        (
            vec!["view", "glosbox", "--play", "no-such-path.json"],
            "cannot read the camera path",
        ),
        (
            vec!["view", "glosbox", "--out", "elsewhere.png"],
            "--out belongs to lustre render",
        ),
        (
            vec!["view", "glosbox", "--camera-path", "no-such-path.json"],
            "the window plays a path with --play",
        ),
    ] {
        let out = support::lustre(&args);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{args:?} succeeded");
        assert!(stderr.contains(expected), "{args:?}: {stderr}");
        assert!(!stderr.contains("panicked"), "{args:?}: {stderr}");
    }
}
