//! A headless `lustre render` without a desktop session writes only lines
//! about the render to stderr: no `error: XDG_RUNTIME_DIR ...` from
//! libwayland, which Mesa's device-select layer reaches through wgpu's
//! Vulkan instance (lustre-mpr's `device.rs` filters it).

use std::process::Command;

/// The lines `lustre render` writes about a render: what it traced, what it renders on, what it wrote.
const RENDER_LINES: &[&str] = &["traced ", "rendering ", "wrote "];

/// The default technique, and `composed` on a scene without a mirror,
/// conductor or glass triangle (no beams to build, and nothing to warn of).
#[test]
fn headless_render_writes_only_lines_about_the_render() {
    for technique in [&[][..], &["--technique", "composed"][..]] {
        render_writes_only_lines_about_the_render(technique);
    }
}

fn render_writes_only_lines_about_the_render(technique: &[&str]) {
    let dir = std::env::temp_dir().join(format!("lustre-headless-stderr-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let out = dir.join("a.png");
    let output = Command::new(env!("CARGO_BIN_EXE_lustre"))
        .args([
            "render",
            "cornell",
            "--size",
            "32x32",
            "--photons",
            "2000",
            "--out",
        ])
        .arg(&out)
        .args(technique)
        .env_remove("XDG_RUNTIME_DIR")
        .env_remove("WAYLAND_DISPLAY")
        .output()
        .expect("the lustre binary runs");
    let _ = std::fs::remove_dir_all(&dir);
    let stderr = String::from_utf8_lossy(&output.stderr);
    if output.status.code() == Some(77) {
        assert!(
            std::env::var_os("LUSTRE_REQUIRE_GPU").is_none(),
            "LUSTRE_REQUIRE_GPU is set but: {stderr}"
        );
        eprintln!("skipping: no GPU adapter ({stderr})");
        return;
    }
    assert!(output.status.success(), "{stderr}");
    let others: Vec<&str> = stderr
        .lines()
        .filter(|line| !RENDER_LINES.iter().any(|start| line.starts_with(start)))
        .collect();
    assert!(
        others.is_empty(),
        "unexpected stderr lines: {others:?}\n{stderr}"
    );
    assert!(stderr.contains("rendering 32x32"), "{stderr}");
}
