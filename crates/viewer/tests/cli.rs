//! The `lustre` command as a user runs it: output, exit codes, one-line errors.

use std::path::PathBuf;
use std::process::{Command, Output};

fn lustre(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_lustre"))
        .args(args)
        .output()
        .expect("the lustre binary runs")
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("lustre-cli-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[test]
fn info_describes_the_builtin_scenes() {
    for scene in ["cornell", "glosbox"] {
        let out = lustre(&["info", scene]);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let text = String::from_utf8(out.stdout).unwrap();
        assert!(text.contains("triangles   36"), "{text}");
        assert!(
            text.contains("surfaces    18 (18 planar, 0 curved)"),
            "{text}"
        );
        assert!(text.contains("lights      1"), "{text}");
    }
    let text = String::from_utf8(lustre(&["info", "glosbox"]).stdout).unwrap();
    assert!(
        text.contains("rough-conductor") && text.contains("blend(diffuse, rough-conductor)"),
        "{text}"
    );
}

#[test]
fn info_reads_obj_files() {
    let dir = scratch("obj");
    std::fs::write(
        dir.join("room.mtl"),
        "newmtl lamp\nKd 0.5 0.5 0.5\nKe 10 10 10\n",
    )
    .unwrap();
    std::fs::write(
        dir.join("room.obj"),
        "mtllib room.mtl\no lamp\nusemtl lamp\nv 0 1 0\nv 0 1 1\nv 1 1 1\nv 1 1 0\nf 1 2 3 4\n",
    )
    .unwrap();
    let out = lustre(&["info", dir.join("room.obj").to_str().unwrap()]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(
        text.contains("triangles   2") && text.contains("area"),
        "{text}"
    );
}

/// Every user error is one line on stderr and a non-zero exit, never a panic.
#[test]
fn bad_input_is_one_clear_line() {
    let dir = scratch("bad");
    std::fs::write(
        dir.join("bad.obj"),
        "v 0 0 0\nv 1 0 0\nv 0 nan 0\nf 1 2 3\n",
    )
    .unwrap();
    let bad_obj = dir.join("bad.obj");
    let cases: Vec<(Vec<String>, &str)> = vec![
        (
            vec!["info".into(), "nosuchscene".into()],
            "neither a built-in scene (cornell, glosbox) nor an existing file",
        ),
        (
            vec!["info".into(), bad_obj.display().to_string()],
            "bad.obj:3",
        ),
        (
            vec![
                "export-mitsuba".into(),
                "cornell".into(),
                dir.join("x.xml").display().to_string(),
                "--size".into(),
                "0x5".into(),
            ],
            "not a size",
        ),
    ];
    for (args, expected) in cases {
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let out = lustre(&args);
        let err = String::from_utf8(out.stderr).unwrap();
        assert!(!out.status.success(), "{args:?} succeeded");
        assert!(err.contains(expected), "{args:?}: {err}");
        assert!(!err.contains("panicked"), "{args:?}: {err}");
        if args[0] == "info" {
            assert_eq!(err.trim_end().lines().count(), 1, "{args:?}: {err}");
        }
    }
}

#[test]
fn export_mitsuba_writes_the_scene_or_names_what_mitsuba_lacks() {
    let dir = scratch("export");
    let xml = dir.join("out/glosbox.xml");
    let out = lustre(&[
        "export-mitsuba",
        "glosbox",
        xml.to_str().unwrap(),
        "--size",
        "64x48",
        "--spp",
        "16",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = std::fs::read_to_string(&xml).unwrap();
    assert!(
        text.contains("roughconductor") && text.contains("blendbsdf"),
        "{text}"
    );
    assert!(text.contains("\"64\"") && text.contains("\"48\""), "{text}");
    // A Phong material has no Mitsuba twin: an error by default, a warning with --approximate.
    std::fs::write(
        dir.join("p.mtl"),
        "newmtl shiny\nKd 0.3 0.3 0.3\nKs 0.5 0.5 0.5\nNs 40\nnewmtl lamp\nKe 5 5 5\n",
    )
    .unwrap();
    std::fs::write(
        dir.join("p.obj"),
        "mtllib p.mtl\nv 0 0 0\nv 1 0 0\nv 1 0 1\nv 0 2 0\nv 1 2 1\nv 1 2 0\nusemtl shiny\nf 1 3 2\nusemtl lamp\nf 4 6 5\n",
    )
    .unwrap();
    let obj = dir.join("p.obj");
    let target = dir.join("p.xml");
    let out = lustre(&[
        "export-mitsuba",
        obj.to_str().unwrap(),
        target.to_str().unwrap(),
    ]);
    let err = String::from_utf8(out.stderr).unwrap();
    assert!(!out.status.success() && err.contains("shiny"), "{err}");
    assert!(!target.exists(), "a failed export left a file behind");
    let out = lustre(&[
        "export-mitsuba",
        obj.to_str().unwrap(),
        target.to_str().unwrap(),
        "--approximate",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(String::from_utf8(out.stderr).unwrap().contains("warning"));
    assert!(target.exists());
}
