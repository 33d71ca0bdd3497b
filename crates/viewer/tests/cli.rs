//! The `lustre` command as a user runs it: output, exit codes, one-line errors.

mod support;

use support::{lustre, render_or_skip, scratch, sidecar};

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
        // The camera, as a camera path's keyframe would name it.
        assert!(
            text.contains(
                "camera      position [0.0000, 0.0000, 3.9000] target [0.0000, 0.0000, 0.0000]"
            ),
            "{text}"
        );
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
    // Every built-in scene is named, in the library's order.
    let known = format!(
        "neither a built-in scene ({}) nor an existing file",
        lustre_geometry::builtin::BUILTIN_SCENES.join(", ")
    );
    let cases: Vec<(Vec<String>, &str)> = vec![
        (vec!["info".into(), "nosuchscene".into()], &known),
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

/// Files in `dir` whose names start with a dot: the temporaries of atomic writes.
fn temporaries(dir: &std::path::Path) -> Vec<String> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with('.'))
        .collect()
}

#[test]
fn render_writes_the_image_and_its_sidecar_and_nothing_else() {
    let dir = scratch("render");
    for (technique, file, extra) in [
        ("splat", "g.exr", &[][..]),
        (
            "splat-direct",
            "g.png",
            &["--light-samples", "3", "--aa", "2"][..],
        ),
    ] {
        let out_path = dir.join(file);
        let mut args = vec![
            "render",
            "glosbox",
            "--technique",
            technique,
            "--photons",
            "5000",
            "--size",
            "48x32",
            "--out",
            out_path.to_str().unwrap(),
        ];
        args.extend_from_slice(extra);
        let Some(out) = render_or_skip("render_writes_the_image_and_its_sidecar", &args) else {
            return;
        };
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        assert!(out_path.exists());
        let sidecar = sidecar(&out_path);
        assert_eq!(sidecar["photons"], 5000);
        assert_eq!(sidecar["technique"], technique);
        assert_eq!(sidecar["size"], serde_json::json!([48, 32]));
        assert!(sidecar["adapter"].as_str().is_some_and(|a| !a.is_empty()));
        if technique == "splat-direct" {
            // Three jittered point lights for glosbox's one area light, two AA samples.
            assert_eq!(sidecar["light_samples"], 3, "{sidecar}");
            assert_eq!(sidecar["direct_lights"], 3, "{sidecar}");
            assert_eq!(sidecar["aa"], 2, "{sidecar}");
        } else {
            assert!(sidecar["light_samples"].is_null(), "{sidecar}");
            assert!(sidecar["aa"].as_u64().is_some_and(|n| n >= 1), "{sidecar}");
        }
        for phase in ["trace", "splat_setup", "frame", "total"] {
            assert!(
                sidecar["timings_ms"][phase]
                    .as_f64()
                    .is_some_and(|t| t >= 0.0),
                "{phase}: {sidecar}"
            );
        }
    }
    let image = lustre_image::read_exr(dir.join("g.exr")).unwrap();
    assert_eq!((image.width(), image.height()), (48, 32));
    // The scene is lit: the mean radiance is positive and finite.
    let mean = lustre_image::metrics::mean(&image);
    assert!(mean.iter().all(|&m| m > 0.0 && m.is_finite()), "{mean:?}");
    assert!(temporaries(&dir).is_empty(), "{:?}", temporaries(&dir));
}

#[test]
fn render_refuses_bad_options_before_writing_anything() {
    let dir = scratch("render-bad");
    let out_exr = dir.join("x.exr");
    let out = out_exr.to_str().unwrap();
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (
            vec!["render", "glosbox", "--out", "x.jpg"],
            "must end in .exr or .png",
        ),
        (
            vec!["render", "glosbox", "--photons", "0", "--out", out],
            "at least one photon",
        ),
        (
            vec!["render", "glosbox", "--kernel-c", "-1", "--out", out],
            "must be positive",
        ),
        (
            vec!["render", "glosbox", "--size", "0x10", "--out", out],
            "between 1 and 16384",
        ),
        (
            vec!["render", "nosuchscene", "--out", out],
            "neither a built-in scene",
        ),
        (
            vec!["render", "glosbox", "--light-samples", "0", "--out", out],
            "--light-samples 0",
        ),
        (
            vec!["render", "glosbox", "--aa", "0", "--out", out],
            "--aa 0",
        ),
        (
            vec![
                "render",
                "glosbox",
                "--emission-samples",
                "5000",
                "--out",
                out,
            ],
            "--emission-samples 5000: at most 4096",
        ),
        (
            vec![
                "render",
                "glosbox",
                "--technique",
                "splat-direct",
                "--beam-roughness",
                "0.1",
                "--out",
                out,
            ],
            "--beam-roughness: only --technique beams and composed",
        ),
        (
            vec![
                "render",
                "glosbox",
                "--technique",
                "beams",
                "--beam-roughness=-1",
                "--out",
                out,
            ],
            "--beam-roughness -1: must be finite and not negative",
        ),
        (
            vec![
                "render",
                "mirrors",
                "--technique",
                "splat-direct",
                "--shadow-depth",
                "1",
                "--out",
                out,
            ],
            "virtual lights belong to --technique mpr",
        ),
        (
            vec![
                "render",
                "stained-glass",
                "--window-texture",
                "0",
                "--out",
                out,
            ],
            "--window-texture 0: expected 1 to 4096 texels",
        ),
        (
            vec![
                "render",
                "mirrors",
                "--technique",
                "mpr",
                "--shadows",
                "maps",
                "--shadow-depth",
                "1",
                "--out",
                out,
            ],
            "virtual lights need --shadows volumes",
        ),
        (
            vec![
                "render",
                "mirrors",
                "--technique",
                "mpr",
                "--shadow-depth",
                "9",
                "--out",
                out,
            ],
            "--shadow-depth 9: at most 8",
        ),
        (
            vec![
                "render",
                "glosbox",
                "--technique",
                "splat-direct",
                "--glossy-images",
                "4",
                "--out",
                out,
            ],
            "only --technique mpr",
        ),
        (
            vec![
                "render",
                "glosbox",
                "--technique",
                "mpr",
                "--diffuse",
                "splat",
                "--glossy-images",
                "4",
                "--out",
                out,
            ],
            "needs --diffuse texture",
        ),
        (
            vec![
                "render",
                "glosbox",
                "--technique",
                "mpr",
                "--spec-depth",
                "0",
                "--glossy-images",
                "4",
                "--out",
                out,
            ],
            "needs --spec-depth",
        ),
        (
            vec![
                "render",
                "glosbox",
                "--technique",
                "mpr",
                "--glossy-images",
                "1000",
                "--out",
                out,
            ],
            "samples exceed",
        ),
        (
            vec![
                "render",
                "glosbox",
                "--technique",
                "ibr",
                "--ibr-maps",
                "0",
                "--out",
                out,
            ],
            "--ibr-maps 0",
        ),
        (
            vec![
                "render",
                "glosbox",
                "--technique",
                "ibr",
                "--ibr-bounces",
                "0",
                "--out",
                out,
            ],
            "--ibr-bounces 0",
        ),
        (
            vec![
                "render",
                "glosbox",
                "--technique",
                "ibr",
                "--diffuse",
                "splat",
                "--out",
                out,
            ],
            "need --diffuse texture",
        ),
        (
            vec![
                "render",
                "glosbox",
                "--technique",
                "ibr",
                "--ibr-arc-step",
                "0.5",
                "--out",
                out,
            ],
            "arc step",
        ),
        (
            vec![
                "render",
                "glosbox",
                "--technique",
                "ibr",
                "--ibr-elements",
                "0x2",
                "--out",
                out,
            ],
            "not a size",
        ),
        (
            vec![
                "render",
                "glosbox",
                "--technique",
                "ibr",
                "--ibr-reflected",
                "geometry",
                "--ibr-cache",
                "maps.ibr",
                "--out",
                out,
            ],
            "capture no maps to cache",
        ),
        (
            vec![
                "render",
                "glosbox",
                "--technique",
                "ibr",
                "--ibr-cache",
                "no-such-directory/maps.ibr",
                "--out",
                out,
            ],
            "does not exist",
        ),
        (
            vec![
                "render",
                "glosbox",
                "--technique",
                "splat-direct",
                "--reflectors",
                "images",
                "--out",
                out,
            ],
            "--reflectors: only --technique composed",
        ),
        (
            vec![
                "render",
                "glosbox",
                "--technique",
                "splat-direct",
                "--caustics",
                "splats",
                "--out",
                out,
            ],
            "--caustics: only --technique composed",
        ),
        (
            vec![
                "render",
                "glosbox",
                "--technique",
                "composed",
                "--reflectors",
                "splats",
                "--glossy-images",
                "4",
                "--out",
                out,
            ],
            "--glossy-images: only --technique mpr, beams and composed (with --reflectors images)",
        ),
        (
            vec![
                "render",
                "glosbox",
                "--technique",
                "composed",
                "--shadow-depth",
                "1",
                "--out",
                out,
            ],
            "virtual lights would add it twice",
        ),
        (
            vec![
                "render",
                "glosbox",
                "--technique",
                "composed",
                "--caustics",
                "splats",
                "--shadow-depth",
                "1",
                "--out",
                out,
            ],
            "use --caustics virtual-lights",
        ),
        (
            vec![
                "render",
                "glosbox",
                "--technique",
                "composed",
                "--caustics",
                "virtual-lights",
                "--shadows",
                "maps",
                "--out",
                out,
            ],
            "--caustics virtual-lights needs --shadows volumes",
        ),
        (
            vec![
                "render",
                "glosbox",
                "--technique",
                "composed",
                "--reflectors",
                "maps",
                "--diffuse",
                "splat",
                "--out",
                out,
            ],
            "need --diffuse texture",
        ),
        (
            vec![
                "render",
                "glosbox",
                "--technique",
                "composed",
                "--diffuse",
                "splat",
                "--out",
                out,
            ],
            "--reflectors images needs --diffuse texture",
        ),
        (
            vec![
                "render",
                "glosbox",
                "--technique",
                "composed",
                "--glossy-images",
                "0",
                "--out",
                out,
            ],
            "--glossy-images 0 with --reflectors images",
        ),
        (
            vec![
                "render",
                "glosbox",
                "--technique",
                "detp",
                "--term-images",
                "--out",
                out,
            ],
            "--terms and --term-images: the per-vertex techniques",
        ),
    ];
    for (args, expected) in cases {
        let result = lustre(&args);
        assert!(!result.status.success(), "{args:?} succeeded");
        let stderr = String::from_utf8_lossy(&result.stderr);
        assert!(stderr.contains(expected), "{args:?}: {stderr}");
        assert!(!stderr.contains("panicked"), "{args:?}: {stderr}");
    }
    assert!(
        std::fs::read_dir(&dir).unwrap().next().is_none(),
        "files were written"
    );
}

/// `--ibr-cache`: the first render captures the radiance maps and writes
/// them, the next one with the same lighting and sampling (another image
/// size) draws from them and gives the image a capture gives, and one with
/// other sampling or a damaged file captures again and rewrites the file.
#[test]
fn the_radiance_map_cache_is_reused_only_for_the_maps_it_holds() {
    let dir = scratch("ibr-cache");
    let cache = dir.join("glosbox.ibr");
    let render = |out: &str, size: &str, map_size: &str| {
        let out_path = dir.join(out);
        let args = [
            "render",
            "glosbox",
            "--technique",
            "ibr",
            "--photons",
            "5000",
            "--seed",
            "3",
            "--size",
            size,
            "--ibr-arc-step",
            "60",
            "--ibr-map-size",
            map_size,
            "--ibr-bounces",
            "1",
            "--ibr-cache",
            cache.to_str().unwrap(),
            "--out",
            out_path.to_str().unwrap(),
        ];
        let out = render_or_skip("the_radiance_map_cache", &args)?;
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
        let hit = sidecar(&out_path)["radiance_maps"]["cache"]["hit"].as_bool();
        Some((lustre_image::read_exr(&out_path).unwrap(), hit, stderr))
    };
    let Some((captured, hit, _)) = render("a.exr", "32x24", "16") else {
        return;
    };
    assert_eq!(hit, Some(false));
    let written = std::fs::read(&cache).unwrap();
    let (from_cache, hit, stderr) = render("b.exr", "32x24", "16").unwrap();
    assert_eq!(hit, Some(true), "{stderr}");
    assert_eq!(captured.into_pixels(), from_cache.into_pixels());
    let (_, hit, _) = render("c.exr", "40x30", "16").unwrap();
    assert_eq!(hit, Some(true), "the image size does not change the maps");
    let (_, hit, stderr) = render("d.exr", "32x24", "12").unwrap();
    assert_eq!(hit, Some(false));
    assert!(stderr.contains("made for other settings"), "{stderr}");
    assert_ne!(
        std::fs::read(&cache).unwrap(),
        written,
        "the cache was rewritten"
    );
    let mut damaged = std::fs::read(&cache).unwrap();
    let middle = damaged.len() / 2;
    damaged[middle] ^= 0xff;
    std::fs::write(&cache, damaged).unwrap();
    let (_, hit, stderr) = render("e.exr", "32x24", "12").unwrap();
    assert_eq!(hit, Some(false));
    assert!(stderr.contains("checksum"), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert!(temporaries(&dir).is_empty(), "{:?}", temporaries(&dir));
}

/// A Phong material with kd + ks > 1 is not energy conserving: the MTL loader
/// only warns, the renderer refuses it and names the material and the scene.
#[test]
fn render_names_a_material_the_brdfs_refuse() {
    let dir = scratch("render-phong");
    std::fs::write(
        dir.join("room.mtl"),
        "newmtl lamp\nKd 0.5 0.5 0.5\nKe 10 10 10\nnewmtl shiny\nKd 0.8 0.8 0.8\nKs 0.6 0.6 0.6\nNs 20\nillum 2\n",
    )
    .unwrap();
    std::fs::write(
        dir.join("room.obj"),
        "mtllib room.mtl\no lamp\nusemtl lamp\nv 0 1 0\nv 1 1 0\nv 1 1 1\nv 0 1 1\nf 1 2 3 4\n\
         o floor\nusemtl shiny\nv -2 0 -2\nv -2 0 2\nv 2 0 2\nv 2 0 -2\nf 5 6 7 8\n",
    )
    .unwrap();
    let out_path = dir.join("room.png");
    let result = lustre(&[
        "render",
        dir.join("room.obj").to_str().unwrap(),
        "--photons",
        "100",
        "--size",
        "8x8",
        "--out",
        out_path.to_str().unwrap(),
    ]);
    assert!(!result.status.success());
    let stderr = String::from_utf8_lossy(&result.stderr);
    assert!(
        stderr.contains("shiny") && stderr.contains("room"),
        "{stderr}"
    );
    assert!(!out_path.exists());
}

#[test]
fn beams_render_the_stained_glass_window_and_record_their_beams() {
    let dir = scratch("beams");
    let out_path = dir.join("sg.exr");
    let args = [
        "render",
        "stained-glass",
        "--technique",
        "beams",
        "--photons",
        "20000",
        "--size",
        "48x32",
        "--aa",
        "1",
        "--out",
        out_path.to_str().unwrap(),
    ];
    let Some(out) = render_or_skip("beams_render_the_stained_glass_window", &args) else {
        return;
    };
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let sidecar = sidecar(&out_path);
    let beams = &sidecar["beams"];
    // One point light through every pane triangle: one transmitted and one
    // reflected beam each, towards opposite sides of the window.
    let scene = lustre_geometry::builtin::stained_glass();
    let panes = lustre_beams::BeamInput::from_scene(&scene)
        .unwrap()
        .scatterers
        .len();
    assert_eq!(beams["scatterers"], panes, "{sidecar}");
    assert_eq!(beams["scattered"], 2 * panes, "{sidecar}");
    assert_eq!(beams["shadow"], 0, "{sidecar}");
    assert!(
        beams["photon_hits_left_to_beams"]
            .as_u64()
            .is_some_and(|n| n > 0),
        "{sidecar}"
    );
    assert_eq!(sidecar["passes"]["shadow_depth"], 0, "{sidecar}");
    let image = lustre_image::read_exr(&out_path).unwrap();
    let mean = lustre_image::metrics::mean(&image);
    assert!(mean.iter().all(|&m| m > 0.0 && m.is_finite()), "{mean:?}");
    assert!(temporaries(&dir).is_empty(), "{:?}", temporaries(&dir));
}

/// `mpr` draws the stained-glass window's light as one virtual light
/// through a projective texture of its 16 panes (section 4.5), or one per
/// pane, and records it in the sidecar.
#[test]
fn mpr_draws_the_stained_glass_window_through_its_projective_texture() {
    let dir = scratch("windows");
    for (pane_light, windows) in [("projective", 1), ("per-pane", 16)] {
        let out_path = dir.join(format!("sg-{pane_light}.exr"));
        let args = [
            "render",
            "stained-glass",
            "--technique",
            "mpr",
            "--pane-light",
            pane_light,
            "--window-texture",
            "64",
            "--photons",
            "20000",
            "--size",
            "48x32",
            "--aa",
            "1",
            "--out",
            out_path.to_str().unwrap(),
        ];
        let Some(out) = render_or_skip("mpr_draws_the_stained_glass_window", &args) else {
            return;
        };
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let sidecar = sidecar(&out_path);
        let w = &sidecar["passes"]["windows"];
        assert_eq!(w["count"], windows, "{sidecar}");
        assert_eq!(w["panes"], 16, "{sidecar}");
        let size = if windows == 1 { 64 } else { 1 };
        assert_eq!(w["texture_size"], size, "{sidecar}");
        assert_eq!(w["texture_bytes"], windows * size * size * 8, "{sidecar}");
        let image = lustre_image::read_exr(&out_path).unwrap();
        let mean = lustre_image::metrics::mean(&image);
        assert!(mean.iter().all(|&m| m > 0.0 && m.is_finite()), "{mean:?}");
    }
    assert!(temporaries(&dir).is_empty(), "{:?}", temporaries(&dir));
}

#[test]
fn beams_refuse_virtual_lights() {
    let dir = scratch("beams-refusal");
    let out_path = dir.join("c.png");
    let out = lustre(&[
        "render",
        "cardioid",
        "--technique",
        "beams",
        "--shadow-depth",
        "1",
        "--out",
        out_path.to_str().unwrap(),
    ]);
    assert!(!out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("the beams draw the light that mirrors and glass send on"),
        "{stderr}"
    );
    assert_eq!(stderr.trim().lines().count(), 1, "{stderr}");
    assert!(!out_path.exists());
}

/// A model as people have them: no light, its MTL file missing. `info` and
/// `render` load it with warnings on stderr (the missing library, the
/// unknown material, the default studio) instead of refusing it, and the
/// sidecar records the studio.
#[test]
fn a_model_without_light_or_mtl_renders_in_a_default_studio() {
    let dir = scratch("studio");
    let obj = dir.join("teapotish.obj");
    std::fs::write(
        &obj,
        "mtllib missing.mtl\nusemtl porcelain\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0.5 0.5 0.8\n\
         f 1 2 5\nf 2 3 5\nf 3 4 5\nf 4 1 5\nf 1 4 3 2\n",
    )
    .unwrap();
    let info = lustre(&["info", obj.to_str().unwrap()]);
    assert!(
        info.status.success(),
        "{}",
        String::from_utf8_lossy(&info.stderr)
    );
    // `info` lists the warnings with the scene.
    let stdout = String::from_utf8_lossy(&info.stdout);
    for needle in ["missing.mtl", "default studio", "studio-light"] {
        assert!(stdout.contains(needle), "{needle}: {stdout}");
    }
    let out_path = dir.join("t.exr");
    let args = small_render(&obj, &out_path);
    let Some(out) = render_or_skip("a_model_without_light_or_mtl_renders", &args) else {
        return;
    };
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(stderr.contains("unknown material `porcelain`"), "{stderr}");
    let sidecar = sidecar(&out_path);
    assert!(
        sidecar["studio"]["radiance"]
            .as_f64()
            .is_some_and(|r| r > 0.0),
        "{sidecar}"
    );
    let image = lustre_image::read_exr(&out_path).unwrap();
    let mean = lustre_image::metrics::mean(&image);
    assert!(mean.iter().all(|&m| m > 0.0 && m.is_finite()), "{mean:?}");
}

/// A glTF 2.0 model (a pyramid in a `.gltf` with its buffer in a `.bin` beside it, no light): `info` lists it and `render` draws it in the default studio.
#[test]
fn gltf_models_are_listed_and_rendered() {
    let dir = scratch("gltf");
    let positions: [[f32; 3]; 5] = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 0.0, 1.0],
        [0.0, 0.0, 1.0],
        [0.5, 0.8, 0.5],
    ];
    // Counter-clockwise seen from outside: the sides, then the base facing down.
    let indices: [u16; 18] = [0, 4, 1, 1, 4, 2, 2, 4, 3, 3, 4, 0, 0, 1, 2, 0, 2, 3];
    let mut bin: Vec<u8> = positions
        .iter()
        .flatten()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    bin.extend(indices.iter().flat_map(|i| i.to_le_bytes()));
    std::fs::write(dir.join("pyramid.bin"), &bin).unwrap();
    let gltf = serde_json::json!({
        "asset": {"version": "2.0"},
        "scenes": [{"nodes": [0]}],
        "nodes": [{"name": "pyramid", "mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "material": 0}]}],
        "materials": [{"name": "clay", "pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.5, 0.3, 1.0], "metallicFactor": 0.0, "roughnessFactor": 1.0}}],
        "buffers": [{"uri": "pyramid.bin", "byteLength": bin.len()}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 60},
            {"buffer": 0, "byteOffset": 60, "byteLength": 36}
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 5, "type": "VEC3", "min": [0, 0, 0], "max": [1, 0.8, 1]},
            {"bufferView": 1, "componentType": 5123, "count": 18, "type": "SCALAR"}
        ]
    });
    let path = dir.join("pyramid.gltf");
    std::fs::write(&path, serde_json::to_vec(&gltf).unwrap()).unwrap();
    let info = lustre(&["info", path.to_str().unwrap()]);
    let stdout = String::from_utf8_lossy(&info.stdout);
    assert!(
        info.status.success(),
        "{}",
        String::from_utf8_lossy(&info.stderr)
    );
    for needle in ["pyramid", "clay", "default studio", "diffuse"] {
        assert!(stdout.contains(needle), "{needle}: {stdout}");
    }
    // Six triangles of the pyramid, four of the studio's two quads.
    assert!(stdout.contains("triangles   10"), "{stdout}");
    let out_path = dir.join("p.exr");
    let args = small_render(&path, &out_path);
    let Some(out) = render_or_skip("gltf_models_are_listed_and_rendered", &args) else {
        return;
    };
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let image = lustre_image::read_exr(&out_path).unwrap();
    let mean = lustre_image::metrics::mean(&image);
    assert!(mean.iter().all(|&m| m > 0.0 && m.is_finite()), "{mean:?}");
    // A broken buffer reference is one clear line naming the file.
    std::fs::remove_file(dir.join("pyramid.bin")).unwrap();
    let out = lustre(&["info", path.to_str().unwrap()]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(
        stderr.contains("pyramid.gltf") && stderr.contains("pyramid.bin"),
        "{stderr}"
    );
    assert!(!stderr.contains("panicked"), "{stderr}");
}

/// `export-gltf` writes a file `info` reads back as the same scene, names each approximation, and refuses another extension before writing anything.
#[test]
fn export_gltf_writes_what_info_reads_back() {
    let dir = scratch("export-gltf");
    let glb = dir.join("glosbox.glb");
    let out = lustre(&["export-gltf", "glosbox", glb.to_str().unwrap()]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(stderr.contains("material `gold`"), "{stderr}");
    let info = lustre(&["info", glb.to_str().unwrap()]);
    let text = String::from_utf8_lossy(&info.stdout);
    assert!(
        info.status.success(),
        "{}",
        String::from_utf8_lossy(&info.stderr)
    );
    assert!(
        text.contains("triangles   36") && text.contains("lights      1"),
        "{text}"
    );
    let bad = dir.join("glosbox.obj");
    let out = lustre(&["export-gltf", "glosbox", bad.to_str().unwrap()]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains(".glb or .gltf"));
    assert!(!bad.exists());
}

/// `--camera-path` renders every frame of a walkthrough through the same frame code as a single render: a path whose keyframes are the scene's own camera gives that render bit for bit in every frame; a bad path or a technique that cannot follow one is refused before any work.
#[test]
fn a_camera_path_renders_the_walkthrough_through_the_same_frame() {
    let dir = scratch("camera-path");
    // glosbox's own camera.
    let key = |t: f32| serde_json::json!({"time": t, "position": [0.0, 0.0, 3.9], "target": [0.0, 0.0, 0.0], "up": [0.0, 1.0, 0.0], "fov_y_degrees": 39.3077});
    let path = dir.join("still.json");
    let doc = serde_json::json!({"format": "lustre-camera-path", "version": 1, "keyframes": [key(0.0), key(1.5)]});
    std::fs::write(&path, serde_json::to_vec(&doc).unwrap()).unwrap();
    let common = [
        "--photons",
        "20000",
        "--size",
        "32x24",
        "--aa",
        "1",
        "--light-samples",
        "1",
    ];
    let single = dir.join("single.exr");
    let mut args = vec!["render", "glosbox"];
    args.extend(common);
    args.extend(["--out", single.to_str().unwrap()]);
    let Some(out) = render_or_skip("a_camera_path_renders_the_walkthrough", &args) else {
        return;
    };
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let walk = dir.join("walk.exr");
    let mut args = vec!["render", "glosbox"];
    args.extend(common);
    args.extend([
        "--camera-path",
        path.to_str().unwrap(),
        "--path-frames",
        "2",
        "--out",
        walk.to_str().unwrap(),
    ]);
    let out = lustre(&args);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let expected = lustre_image::read_exr(&single).unwrap();
    for frame in ["walk-0000.exr", "walk-0001.exr"] {
        assert_eq!(
            lustre_image::read_exr(dir.join(frame)).unwrap(),
            expected,
            "{frame}"
        );
    }
    assert!(!walk.exists(), "a walkthrough writes numbered frames only");
    let sidecar = sidecar(&walk);
    assert_eq!(sidecar["camera_path"]["frames"], 2);
    assert_eq!(
        sidecar["camera_path"]["frame_ms"].as_array().unwrap().len(),
        2
    );

    // Refusals, each before any work: a bad file, a per-vertex technique, --frames.
    std::fs::write(
        dir.join("bad.json"),
        "{\"format\": \"lustre-camera-path\", \"version\": 1, \"keyframes\": []}",
    )
    .unwrap();
    let bad = dir.join("bad.json");
    for (extra, expected) in [
        (
            vec!["--camera-path", bad.to_str().unwrap()],
            "needs a keyframe",
        ),
        (
            vec![
                "--camera-path",
                path.to_str().unwrap(),
                "--technique",
                "detp",
            ],
            "per-vertex techniques",
        ),
        (
            vec![
                "--camera-path",
                path.to_str().unwrap(),
                "--path-frames",
                "0",
            ],
            "--path-frames 0",
        ),
    ] {
        let out_path = dir.join("refused.png");
        let mut args = vec!["render", "glosbox", "--out", out_path.to_str().unwrap()];
        args.extend(extra);
        let out = lustre(&args);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(
            !out.status.success() && stderr.contains(expected),
            "{expected}: {stderr}"
        );
        assert!(
            !stderr.contains("traced"),
            "refused after tracing: {stderr}"
        );
        assert!(!out_path.exists() && !dir.join("refused-0000.png").exists());
    }
}

/// `lustre render MODEL` small and quick: 20,000 photons, 32 × 32, one sample per pixel, one light sample, into `out`.
fn small_render<'a>(model: &'a std::path::Path, out: &'a std::path::Path) -> [&'a str; 12] {
    [
        "render",
        model.to_str().unwrap(),
        "--photons",
        "20000",
        "--size",
        "32x32",
        "--aa",
        "1",
        "--light-samples",
        "1",
        "--out",
        out.to_str().unwrap(),
    ]
}

/// An output in a directory that does not exist is refused before any photon is traced.
#[test]
fn a_missing_output_directory_is_refused_before_any_work() {
    let dir = scratch("missing-dir");
    let out_path = dir.join("nowhere").join("r.png");
    let out = lustre(&["render", "glosbox", "--out", out_path.to_str().unwrap()]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{stderr}");
    assert!(
        stderr.contains("does not exist") && stderr.contains("nowhere"),
        "{stderr}"
    );
    assert!(
        !stderr.contains("traced"),
        "refused after tracing: {stderr}"
    );
    assert_eq!(stderr.trim().lines().count(), 1, "{stderr}");
}
