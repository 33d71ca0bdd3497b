//! `cargo xtask bench`: runs the criterion benches and writes BENCHMARKS.md
//! from their medians.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use anyhow::Context;
use serde_json::Value;

/// The criterion benches to run: (package, bench target).
const BENCHES: &[(&str, &str)] = &[
    ("lustre-geometry", "bvh"),
    ("lustre-brdf", "brdf"),
    ("lustre-photon", "trace"),
    ("lustre-mpr", "splat"),
    ("lustre-density", "detp"),
    ("lustre-density", "quasi_static"),
    // DETP on a 71,820-triangle glossy model (issue 15): minutes per run.
    ("lustre-density", "dense_glossy"),
];

/// One criterion result.
struct Measurement {
    id: String,
    median_ns: f64,
    elements: Option<f64>,
}

/// Runs every bench (or only those whose target matches `filter`) and
/// rewrites BENCHMARKS.md: the CPU tables from criterion's medians (kept as
/// they were when the filter ran none of their benches), the marker-delimited
/// sections other subcommands own, the `splat` section
/// ([`SPLAT_SECTION`]) from the splat bench's results and the JSON files it
/// writes beside them, and the `embree` section (our BVH against Embree,
/// [`crate::embree::run`]) when the filter matches `embree`.
pub fn run(filter: Option<&str>) -> anyhow::Result<()> {
    let selected = |bench: &str| filter.is_none_or(|f| bench.contains(f));
    // Only results this run wrote count: criterion keeps every earlier run's
    // results (another size, another bench's configuration) beside them.
    // One second of slack for file systems with coarse timestamps.
    let started = std::time::SystemTime::now() - std::time::Duration::from_secs(1);
    for (package, bench) in BENCHES {
        if selected(bench) {
            crate::ci::cargo(&["bench", "-p", package, "--bench", bench, "--", "--noplot"])?;
        }
    }
    let root = crate::workspace_root();
    let criterion = criterion_dir(&root);
    let mut results = Vec::new();
    collect(&criterion, &mut results, started)?;
    results.sort_by(|a, b| a.id.cmp(&b.id));
    let path = root.join("BENCHMARKS.md");
    let previous = std::fs::read_to_string(&path).unwrap_or_default();
    // The CPU tables are rewritten only when every CPU bench ran (from this
    // run's results alone); otherwise they stay as they were.
    let cpu_ran = BENCHES
        .iter()
        .filter(|(_, bench)| !matches!(*bench, "splat" | "detp" | "quasi_static" | "dense_glossy"))
        .all(|(_, bench)| selected(bench));
    let mut text = if cpu_ran || previous.is_empty() {
        let mut text = render(&results);
        // Keep the marker-delimited sections other subcommands own (`converge`).
        for section in sections(&previous) {
            text.push('\n');
            text.push_str(section);
            text.push('\n');
        }
        text
    } else {
        previous
    };
    let splat_setups = read_splat_setups(&criterion.join(SPLAT_GROUP), started)?;
    if !splat_setups.is_empty() {
        let mut body = String::new();
        splat_tables(&mut body, &results, &splat_setups);
        text = replace_section(&text, SPLAT_SECTION, body.trim_start_matches('\n'));
    }
    // Both density benches write one section: rewrite it only when both ran.
    let density_ran = ["detp", "quasi_static"].iter().all(|b| selected(b));
    if !density_ran && ["detp", "quasi_static"].iter().any(|b| selected(b)) {
        println!(
            "xtask: the density section needs both the detp and quasi_static benches; left as it was"
        );
    }
    let density = density_tables(
        &results,
        &criterion.join(QUASI_STATIC_GROUP),
        started,
        &machine(),
        std::env::var_os("DETP_BENCH_FULL").is_some(),
    )?;
    if density_ran && !density.is_empty() {
        text = replace_section(&text, DENSITY_SECTION, density.trim_start_matches('\n'));
    }
    // Our BVH against Embree: its own section, rewritten whenever it ran.
    if selected("embree") {
        let body = crate::embree::run()?;
        text = replace_section(&text, crate::embree::SECTION, &body);
    }
    let tmp = path.with_extension("md.tmp");
    std::fs::write(&tmp, text).with_context(|| format!("cannot write {}", tmp.display()))?;
    std::fs::rename(&tmp, &path).with_context(|| format!("cannot write {}", path.display()))?;
    println!("xtask: wrote {}", path.display());
    Ok(())
}

/// Where criterion writes its results, chosen as criterion chooses:
/// `$CRITERION_HOME`, else `$CARGO_TARGET_DIR/criterion`, else the
/// workspace's `target/criterion`.
fn criterion_dir(root: &Path) -> PathBuf {
    if let Some(home) = std::env::var_os("CRITERION_HOME") {
        return home.into();
    }
    if let Some(target) = std::env::var_os("CARGO_TARGET_DIR") {
        return PathBuf::from(target).join("criterion");
    }
    root.join("target/criterion")
}

/// The markers around the section `name` of BENCHMARKS.md.
fn markers(name: &str) -> (String, String) {
    (
        format!("<!-- {name}:start -->"),
        format!("<!-- {name}:end -->"),
    )
}

/// The sections `<!-- NAME:start -->` … `<!-- NAME:end -->` of `doc`, each
/// with its markers, in order.
pub fn sections(doc: &str) -> Vec<&str> {
    let mut found = Vec::new();
    let mut from = 0;
    while let Some(offset) = doc[from..].find("<!-- ") {
        let start = from + offset;
        let name = doc[start + 5..]
            .split_once(" -->")
            .and_then(|(marker, _)| marker.strip_suffix(":start"));
        let end = name.and_then(|name| {
            let end_marker = markers(name).1;
            doc[start..]
                .find(&end_marker)
                .map(|i| start + i + end_marker.len())
        });
        match end {
            Some(end) => {
                found.push(&doc[start..end]);
                from = end;
            }
            None => from = start + 5,
        }
    }
    found
}

/// `doc` with the section `name` replaced by `body` between its markers,
/// or appended at the end when the markers are missing; the rest is kept.
pub fn replace_section(doc: &str, name: &str, body: &str) -> String {
    let (start_marker, end_marker) = markers(name);
    let section = format!(
        "{start_marker}\n{}\n{end_marker}",
        body.trim_end_matches('\n')
    );
    let span = doc.find(&start_marker).and_then(|start| {
        doc[start..]
            .find(&end_marker)
            .map(|end| (start, start + end + end_marker.len()))
    });
    if let Some((start, end)) = span {
        return format!("{}{section}{}", &doc[..start], &doc[end..]);
    }
    let mut out = doc.to_owned();
    if !out.is_empty() {
        if !out.ends_with('\n') {
            out.push('\n');
        }
        out.push('\n');
    }
    out.push_str(&section);
    out.push('\n');
    out
}

/// Replaces the section `name` of BENCHMARKS.md (created when missing) by `body`, atomically.
pub fn write_section(name: &str, body: &str) -> anyhow::Result<()> {
    let path = crate::workspace_root().join("BENCHMARKS.md");
    let doc = match std::fs::read_to_string(&path) {
        Ok(doc) => doc,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => String::new(),
        Err(e) => return Err(e).with_context(|| format!("cannot read {}", path.display())),
    };
    lustre_image::write_bytes_atomic(&path, replace_section(&doc, name, body).as_bytes())?;
    println!("xtask: wrote the {name} section of {}", path.display());
    Ok(())
}

/// Whether the file at `path` was modified at or after `since`.
fn written_since(path: &Path, since: std::time::SystemTime) -> bool {
    std::fs::metadata(path)
        .and_then(|m| m.modified())
        .is_ok_and(|t| t >= since)
}

/// Finds every `new/benchmark.json` + `new/estimates.json` pair under `dir`
/// whose estimates were written at or after `since` (this run's results).
fn collect(
    dir: &Path,
    out: &mut Vec<Measurement>,
    since: std::time::SystemTime,
) -> anyhow::Result<()> {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return Ok(());
    };
    for entry in entries {
        let path = entry?.path();
        if !path.is_dir() {
            continue;
        }
        if path.file_name().is_some_and(|n| n == "new") {
            if !written_since(&path.join("estimates.json"), since) {
                continue;
            }
            let read = |name: &str| -> anyhow::Result<Value> {
                let p = path.join(name);
                let text = std::fs::read_to_string(&p)
                    .with_context(|| format!("cannot read {}", p.display()))?;
                serde_json::from_str(&text).with_context(|| format!("{} is not JSON", p.display()))
            };
            let (benchmark, estimates) = (read("benchmark.json")?, read("estimates.json")?);
            out.push(Measurement {
                id: benchmark["full_id"].as_str().unwrap_or("?").to_owned(),
                median_ns: estimates["median"]["point_estimate"]
                    .as_f64()
                    .unwrap_or(f64::NAN),
                elements: benchmark["throughput"]["Elements"].as_f64(),
            });
        } else {
            collect(&path, out, since)?;
        }
    }
    Ok(())
}

/// The median of some values (the mean of the two middle ones for an even count; NaN for none).
pub fn median(mut values: Vec<f64>) -> f64 {
    values.sort_by(f64::total_cmp);
    let n = values.len();
    match n {
        0 => f64::NAN,
        _ if n % 2 == 1 => values[n / 2],
        _ => 0.5 * (values[n / 2 - 1] + values[n / 2]),
    }
}

/// The machine this runs on, from /proc/cpuinfo.
pub fn machine() -> String {
    let cpu = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split_once(':'))
                .map(|(_, v)| v.trim().to_owned())
        })
        .unwrap_or_else(|| "unknown CPU".into());
    let cores = std::thread::available_parallelism().map_or(0, |n| n.get());
    format!("{cpu}, {cores} cores available")
}

fn render(results: &[Measurement]) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "# Benchmarks\n");
    let _ = writeln!(
        s,
        "Written by `cargo xtask bench` from criterion medians; do not edit by hand.\n"
    );
    let _ = writeln!(
        s,
        "Each section names the machine (and adapter) it ran on. The BVH, BRDF and photon \
         tracing tables: {}, CPU only.\n",
        machine()
    );
    let _ = writeln!(s, "## BVH closest hit (lustre-geometry, obvhs CWBVH)\n");
    let _ = writeln!(
        s,
        "65,536 rays per batch, rayon-parallel: coherent rays are one primary ray per pixel of a \
         256×256 image; incoherent rays start at random points inside the scene's bounds in \
         uniformly random directions. `spheres-516k` is 64 UV spheres of 8,064 triangles \
         (516,096 triangles). `coherent-obvhs-baseline` traces the same coherent rays with obvhs \
         alone (its CWBVH traversal and its own triangle test, returning only the distance); ours \
         (`coherent`) runs on our eight-wide BVH and returns full hit records (barycentrics, \
         normals, UVs, surface and material ids). The `embree` section compares with Embree.\n"
    );
    let _ = writeln!(s, "| benchmark | median time per batch | rays/s |");
    let _ = writeln!(s, "|---|---:|---:|");
    for r in results
        .iter()
        .filter(|r| r.id.starts_with("bvh-closest-hit/"))
    {
        let per_s = r.elements.map_or("-".into(), |n| {
            format!("{:.2} M", n / (r.median_ns * 1e-9) / 1e6)
        });
        let _ = writeln!(
            s,
            "| {} | {:.2} ms | {per_s} |",
            r.id.trim_start_matches("bvh-closest-hit/"),
            r.median_ns / 1e6
        );
    }
    brdf_table(&mut s, results);
    photon_table(&mut s, results);
    s
}

/// Photons and bounces traced per second (group `trace_glosbox` of lustre-photon's bench).
fn photon_table(s: &mut String, results: &[Measurement]) {
    let rows: Vec<&Measurement> = results
        .iter()
        .filter(|r| r.id.starts_with("trace_glosbox/"))
        .collect();
    if rows.is_empty() {
        return;
    }
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get()) as f64;
    let _ = writeln!(s, "\n## Photon tracing (lustre-photon, section 2.1)\n");
    let _ = writeln!(
        s,
        "`glosbox`, 20,000 photons per iteration, rayon over all cores; a bounce is one hit \
         record. Target: 2 M bounces/s per core.\n"
    );
    let _ = writeln!(
        s,
        "| benchmark | median time | per second | per second per core |"
    );
    let _ = writeln!(s, "|---|---:|---:|---:|");
    for r in rows {
        let Some(n) = r.elements else { continue };
        let per_s = n / (r.median_ns * 1e-9);
        let _ = writeln!(
            s,
            "| {} | {:.2} ms | {:.2} M | {:.2} M |",
            r.id.trim_start_matches("trace_glosbox/"),
            r.median_ns / 1e6,
            per_s / 1e6,
            per_s / cores / 1e6
        );
    }
}

/// The marker-delimited section of BENCHMARKS.md that holds the splat bench's tables.
const SPLAT_SECTION: &str = "splat";

/// Criterion group of lustre-mpr's splat bench; its folder also holds one `<configuration>.json` per configuration.
const SPLAT_GROUP: &str = "splat_glosbox";

/// The configurations lustre-mpr's splat bench knows, in table order.
const SPLAT_CONFIGS: &[&str] = &[
    "full-250k",
    "full-1M",
    "full-250k-c16",
    "optimised-250k",
    "optimised-1M",
    "optimised-250k-c16",
];

/// One configuration of the splat bench as it described itself (`splat_glosbox/<name>.json`).
struct SplatSetup {
    name: String,
    adapter: String,
    software: bool,
    hdr_format: String,
    width: u64,
    height: u64,
    kernel_c: f64,
    emitted: u64,
    hit_records: u64,
    splats: u64,
    /// Fraction of all cores busy while the configuration was measured, and the bench's share.
    cpu_busy: Option<(f64, f64)>,
}

/// Reads every `<configuration>.json` the splat bench wrote in `dir` at or after `since`, in [`SPLAT_CONFIGS`] order.
fn read_splat_setups(dir: &Path, since: std::time::SystemTime) -> anyhow::Result<Vec<SplatSetup>> {
    let mut setups = Vec::new();
    for name in SPLAT_CONFIGS {
        let path = dir.join(format!("{name}.json"));
        if !written_since(&path, since) {
            continue;
        }
        let Ok(text) = std::fs::read_to_string(&path) else {
            continue;
        };
        let v: Value = serde_json::from_str(&text)
            .with_context(|| format!("{} is not JSON", path.display()))?;
        let text_of = |key: &str| v[key].as_str().unwrap_or("?").to_owned();
        let number = |key: &str| v[key].as_u64().unwrap_or(0);
        setups.push(SplatSetup {
            name: (*name).to_owned(),
            adapter: text_of("adapter"),
            software: v["software"].as_bool().unwrap_or(false),
            hdr_format: text_of("hdr_format"),
            width: number("width"),
            height: number("height"),
            kernel_c: v["kernel_c"].as_f64().unwrap_or(f64::NAN),
            emitted: number("emitted"),
            hit_records: number("hit_records"),
            splats: number("splats"),
            cpu_busy: v["cpu_busy"].as_f64().zip(v["cpu_bench"].as_f64()),
        });
    }
    Ok(setups)
}

/// A count in thousands or millions: `574k`, `2.31M`.
fn count(n: u64) -> String {
    if n >= 1_000_000 {
        format!("{:.2}M", n as f64 / 1e6)
    } else {
        format!("{}k", (n as f64 / 1e3).round())
    }
}

/// A duration in milliseconds, three significant figures at most.
fn millis(ms: f64) -> String {
    if ms >= 100.0 {
        format!("{ms:.0} ms")
    } else if ms >= 10.0 {
        format!("{ms:.1} ms")
    } else {
        format!("{ms:.2} ms")
    }
}

/// The splat bench's medians for one configuration: frame ms per restriction and the splat pass alone.
struct SplatTimes {
    frame_surface_id: Option<f64>,
    frame_stencil: Option<f64>,
    splat_pass: Option<f64>,
}

impl SplatTimes {
    fn of(results: &[Measurement], name: &str) -> Self {
        let median = |suffix: &str| {
            let id = format!("{SPLAT_GROUP}/{name}/{suffix}");
            results
                .iter()
                .find(|r| r.id == id)
                .map(|r| r.median_ns / 1e6)
        };
        Self {
            frame_surface_id: median("surface-id/frame"),
            frame_stencil: median("stencil/frame"),
            splat_pass: median("splats"),
        }
    }
}

/// "Photon splatting" (the splat bench of lustre-mpr) and "Paper tables 1 and 2 beside ours".
fn splat_tables(s: &mut String, results: &[Measurement], setups: &[SplatSetup]) {
    let Some(first) = setups.first() else {
        return;
    };
    let show = |ms: Option<f64>| ms.map_or("–".into(), millis);
    let seconds = |ms: Option<f64>| ms.map_or("–".into(), |ms| format!("{:.2}", ms / 1e3));
    let mut adapters: Vec<&str> = setups.iter().map(|x| x.adapter.as_str()).collect();
    adapters.dedup();
    let _ = writeln!(
        s,
        "\n## Photon splatting (lustre-mpr, sections 2.2 and 2.2.1)\n"
    );
    let _ = writeln!(
        s,
        "`glosbox` at {}×{}, C in equation 3 as each row says ({} unless the name ends in `-c16`: \
         `lustre render` defaults to 16, whose splats cover 16 times the pixels, and the \
         fill-bound frames grow about as C²), Silverman's kernel \
         evaluated at pixel centres, exact BRDFs, diffuse surfaces splatted too (no precomputed \
         textures), {} HDR target. Machine: {}. Adapter: {}.\n",
        first.width,
        first.height,
        first.kernel_c,
        first.hdr_format,
        machine(),
        adapters.join("; ")
    );
    let _ = writeln!(
        s,
        "A frame is encode + submit + wait, from the median of 10 frames. `full` (section 2.2) \
         clears, draws the depth pre-pass and splats every hit record. `optimised` (section \
         2.2.1; the area light as a cosine point light of equal power) clears, draws the depth \
         pre-pass and the direct light with the light's shadow cube (drawn once per light pose, \
         outside the frame) and splats the hits with more than one bounce; it traces as many \
         photons as give about 250k or 1M of those. Photons are traced once per configuration \
         (Sobol', seed 1). Splats/s is the splat count over the median of the splat pass alone \
         (surface-id restriction, on the previous frame's depth and ids). Times are wall-clock: \
         where other work kept the cores busy (last column: all work, then this bench's share), \
         frames are longer than on an idle machine. Written by `cargo xtask bench splat` from \
         `{SPLAT_GROUP}/*.json` beside criterion's results.\n"
    );
    let _ = writeln!(
        s,
        "| configuration | C | photons emitted | splats | median frame, surface-id | median frame, \
         stencil | splat pass alone | splats/s | cores busy |"
    );
    let _ = writeln!(s, "|---|---:|---:|---:|---:|---:|---:|---:|---:|");
    for x in setups {
        let t = SplatTimes::of(results, &x.name);
        let rate = t.splat_pass.map_or("–".into(), |ms| {
            let r = x.splats as f64 / (ms / 1e3);
            if r >= 1e6 {
                format!("{:.2} M", r / 1e6)
            } else {
                format!("{:.0} k", r / 1e3)
            }
        });
        let busy = x.cpu_busy.map_or("–".into(), |(all, bench)| {
            format!("{:.0}% / {:.0}%", all * 100.0, bench * 100.0)
        });
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {} | {} | {} | {rate} | {busy} |",
            x.name,
            x.kernel_c,
            count(x.emitted),
            count(x.splats),
            show(t.frame_surface_id),
            show(t.frame_stencil),
            show(t.splat_pass)
        );
    }
    let missing: Vec<&str> = SPLAT_CONFIGS
        .iter()
        .copied()
        .filter(|n| !setups.iter().any(|x| x.name == *n))
        .collect();
    if !missing.is_empty() {
        let _ = writeln!(
            s,
            "\nNot measured: {}. On a software adapter the bench runs only the 250k \
             configurations by default, to finish in about 20 minutes; \
             `LUSTRE_BENCH_SPLAT_MAX=1000000 cargo xtask bench splat` measures all. The `-c16` \
             configurations measure only the surface-id frame.",
            missing.join(", ")
        );
    }

    // The paper's tables 1 and 2 (section 4) with our Glosbox rows.
    let (surfaces, triangles) = lustre_geometry::builtin("glosbox")
        .map(|g| (g.surfaces().len(), g.triangle_count()))
        .unwrap_or((0, 0));
    let _ = writeln!(s, "\n## Paper tables 1 and 2 beside ours\n");
    let _ = writeln!(
        s,
        "The paper (section 4) ran on an SGI Onyx InfiniteReality with 2 raster managers \
         (OpenGL, 12 bits per channel, resolution not stated) and averaged seconds per frame \
         along a camera path; ours are the medians above at one view, {}×{}, on {}. The Simple \
         (3 polygons) and Office (4,072 polygons, MGF) scenes do not exist in Lustre, so only \
         the Glosbox rows have our figures. Our `glosbox` has {surfaces} surfaces ({triangles} \
         triangles). Table 1 may count photon hits rather than emitted photons (figure 3 shows \
         \"one million photon hits\"); our `full-*` rows emit the stated number of photons. C is \
         the kernel constant of equation 3 (support h = C √(A/n)): the paper used 30 to 50, \
         `lustre render` defaults to 16, and the splat bench uses the C of each row; the splat \
         area, and so the fill-bound splat pass, grows about as C².\n",
        first.width,
        first.height,
        adapters.join("; ")
    );
    let ours = |prefix: &str| -> Vec<(&SplatSetup, SplatTimes)> {
        setups
            .iter()
            .filter(|x| x.name.starts_with(prefix))
            .map(|x| (x, SplatTimes::of(results, &x.name)))
            .collect()
    };
    let paper_table = |s: &mut String,
                       title: &str,
                       photons_header: &str,
                       rows: &[(&str, &str, &str, &str)],
                       glosbox: &[(&SplatSetup, SplatTimes)]| {
        let _ = writeln!(s, "{title}\n");
        let _ = writeln!(
            s,
            "| scene | polygons | {photons_header} | paper s/frame | ours | our C | our splats | our \
             s/frame, surface-id | our s/frame, stencil |"
        );
        let _ = writeln!(s, "|---|---:|---:|---:|---|---:|---:|---:|---:|");
        for &(scene, polygons, photons, paper) in rows {
            if scene != "Glosbox" {
                let _ = writeln!(
                    s,
                    "| {scene} | {polygons} | {photons} | {paper} | no such scene in Lustre | – | – \
                     | – | – |"
                );
                continue;
            }
            if glosbox.is_empty() {
                let _ = writeln!(
                    s,
                    "| {scene} | {polygons} | {photons} | {paper} | not measured | – | – | – | – |"
                );
            }
            for (i, (x, t)) in glosbox.iter().enumerate() {
                let paper_cells = if i == 0 {
                    format!("{scene} | {polygons} | {photons} | {paper}")
                } else {
                    "| | |".to_owned()
                };
                let _ = writeln!(
                    s,
                    "| {paper_cells} | `{}`: {} photons emitted, {} hit records | {} | {} | {} | {} |",
                    x.name,
                    count(x.emitted),
                    count(x.hit_records),
                    x.kernel_c,
                    count(x.splats),
                    seconds(t.frame_surface_id),
                    seconds(t.frame_stencil)
                );
            }
        }
        let _ = writeln!(s);
    };
    // Our 1M row first beside the paper's 1.0M, then the others.
    let mut full = ours("full-");
    full.sort_by_key(|(x, _)| !x.name.ends_with("-1M"));
    paper_table(
        s,
        "Table 1, section 2.2 (every hit splatted):",
        "photons",
        &[
            ("Simple", "3", "0.5M", "2.15"),
            ("Glosbox", "18", "1.0M", "4.21"),
            ("Office", "4072", "2.5M", "10.5"),
        ],
        &full,
    );
    paper_table(
        s,
        "Table 2, section 2.2.1 (direct light by shadow maps, indirect hits splatted):",
        "indirect photons",
        &[
            ("Glosbox", "18", "0.25M", "1.18"),
            ("Office", "4072", "0.75M", "3.46"),
        ],
        &ours("optimised-"),
    );
    let rates: Vec<f64> = setups
        .iter()
        .filter_map(|x| {
            SplatTimes::of(results, &x.name)
                .splat_pass
                .map(|ms| x.splats as f64 / (ms / 1e3))
        })
        .collect();
    if let (Some(lo), Some(hi)) = (
        rates.iter().copied().reduce(f64::min),
        rates.iter().copied().reduce(f64::max),
    ) {
        let _ = writeln!(
            s,
            "Splat rate: the paper measured about 246k splat triangles/s (SGI specifies 10M \
             triangles/s); ours, splat pass alone: {:.0}k to {:.0}k splats/s ({:.2}× to {:.2}× \
             the paper's).\n",
            lo / 1e3,
            hi / 1e3,
            lo / 246e3,
            hi / 246e3
        );
    }

    // The issue's targets: 1M splats at 640×480 in 250 ms (software, 2 cores) or 5 ms (GPU).
    let nearest = setups
        .iter()
        .filter_map(|x| {
            SplatTimes::of(results, &x.name)
                .splat_pass
                .map(|ms| (x, ms * 1e6 / x.splats as f64))
        })
        .min_by(|a, b| {
            let d = |x: &SplatSetup| (x.splats as f64 / 1e6).ln().abs();
            d(a.0).total_cmp(&d(b.0))
        });
    let _ = write!(
        s,
        "Targets: 1M splats at 640×480 in under 250 ms with the software driver on 2 cores, \
         under 5 ms on a real GPU. "
    );
    match nearest {
        None => {
            let _ = writeln!(s, "Not measured.");
        }
        Some((x, ms)) => {
            let (target, which, other) = if x.software {
                (
                    250.0,
                    "Software driver",
                    "Real GPU: not measured (no hardware adapter).",
                )
            } else {
                (5.0, "Real GPU", "Software driver: not measured here.")
            };
            let verdict = if ms <= target {
                format!("met, {:.0}% under", (1.0 - ms / target) * 100.0)
            } else {
                format!(
                    "missed by {:.1}× ({} over)",
                    ms / target,
                    millis(ms - target)
                )
            };
            let _ = writeln!(
                s,
                "{which}: {} per 1M splats (the splat pass alone of `{}`, {} splats, scaled to \
                 1M), against {target} ms: {verdict}. {other}",
                millis(ms),
                x.name,
                count(x.splats)
            );
        }
    }
}

/// Per model: evaluations/s and samples/s (groups `eval` and `sample` of lustre-brdf's bench).
fn brdf_table(s: &mut String, results: &[Measurement]) {
    let rate = |group: &str, model: &str| {
        results
            .iter()
            .find(|r| r.id == format!("{group}/{model}"))
            .and_then(|r| r.elements.map(|n| n / (r.median_ns * 1e-9) / 1e6))
    };
    let mut models: Vec<&str> = results
        .iter()
        .filter_map(|r| {
            r.id.strip_prefix("eval/")
                .or_else(|| r.id.strip_prefix("sample/"))
        })
        .collect();
    models.sort_unstable();
    models.dedup();
    if models.is_empty() {
        return;
    }
    let _ = writeln!(s, "\n## BRDF evaluation and sampling (lustre-brdf)\n");
    let _ = writeln!(
        s,
        "Single thread, a batch of random direction pairs per iteration; millions per second.\n"
    );
    let _ = writeln!(s, "| model | evaluations/s | samples/s |");
    let _ = writeln!(s, "|---|---:|---:|");
    let show = |v: Option<f64>| v.map_or("-".into(), |v| format!("{v:.2} M"));
    for m in models {
        let _ = writeln!(
            s,
            "| {m} | {} | {} |",
            show(rate("eval", m)),
            show(rate("sample", m))
        );
    }
}

/// The marker-delimited section of BENCHMARKS.md that holds lustre-density's benches.
const DENSITY_SECTION: &str = "density";

/// Criterion group of lustre-density's quasi_static bench; its folder also holds one `<estimator>-<photons>.json` per configuration.
const QUASI_STATIC_GROUP: &str = "quasi_static_tree";

/// The paper's per-frame figures on its tree scene (García et al. 2003, tables 2.6 and 2.7): photons, seconds per frame.
const PAPER_FRAMES: &[(u64, f64)] = &[(1_000, 0.11), (10_000, 0.46)];

/// The issue's target: a full frame within 40 ms at 100,000 photons on the tree scene.
const TARGET_FRAME_MS: f64 = 40.0;

/// "Quasi-static recalculation" (the quasi_static bench) and "DETP speed-ups" (the detp bench), empty when neither ran.
/// The quasi-static and DETP speed-up sections from this run's results and
/// the quasi_static bench's JSON files in `dir` written at or after `since`,
/// naming `machine` and the DETP bench's size (`full`: `DETP_BENCH_FULL` set).
fn density_tables(
    results: &[Measurement],
    dir: &Path,
    since: std::time::SystemTime,
    machine: &str,
    full: bool,
) -> anyhow::Result<String> {
    let mut s = String::new();
    let mut setups: Vec<(String, Value)> = Vec::new();
    if let Ok(entries) = std::fs::read_dir(dir) {
        for entry in entries.flatten() {
            let path = entry.path();
            if path.extension().is_some_and(|e| e == "json") && written_since(&path, since) {
                let text = std::fs::read_to_string(&path)
                    .with_context(|| format!("cannot read {}", path.display()))?;
                let value: Value = serde_json::from_str(&text)
                    .with_context(|| format!("{} is not JSON", path.display()))?;
                let name = path
                    .file_stem()
                    .and_then(|n| n.to_str())
                    .unwrap_or("")
                    .to_owned();
                setups.push((name, value));
            }
        }
    }
    setups.sort_by_key(|(_, v)| {
        (
            v["photons"].as_u64().unwrap_or(0),
            v["estimator"].as_str().unwrap_or("").to_owned(),
        )
    });
    if !setups.is_empty() {
        let _ = writeln!(
            s,
            "\n## Quasi-static recalculation (lustre-density, García et al. 2003, section 2)\n"
        );
        let _ = writeln!(
            s,
            "The `tree` scene (71,966 static triangles, section 2.9) with its 500-triangle ball rolling \
             along its path; one iteration is one frame: the photosimulation update (figure 2.2) and the \
             radiosity recalculation (equation 2.4 on static vertices, the full estimate on the ball's, \
             figure 2.4 for Impact Count, a full estimate for Photon Maps), including each point's \
             irradiance. DETP uses the paper's radius, 1 % of the scene (0.02 m), and the tuned disc \
             index; the `detp_<speed-up>` rows use the Möller pre-test, the sorted ray cache, the \
             segment grid (cells 2r) or brute force instead (sections 2.6–2.8); Photon Maps k = 50. Median over the frames criterion ran. \
             Machine: {machine}, CPU only (rayon over all cores). Memory per photon is the ray set's bytes (primary rays \
             and their segments) over the photons emitted. Written by `cargo xtask bench quasi_static` \
             (`LUSTRE_BENCH_DENSITY_MAX=1000000` adds 1M photons).\n"
        );
        let _ = writeln!(
            s,
            "| estimator | photons | segments | points | first frame: photosimulation / radiosity | frame (criterion median) | photosimulation update | radiosity | recalculated paths | ray set bytes per photon |"
        );
        let _ = writeln!(s, "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|");
        for (name, v) in &setups {
            let frame = results
                .iter()
                .find(|r| r.id == format!("{QUASI_STATIC_GROUP}/{name}"))
                .map(|r| r.median_ns / 1e6);
            let num = |key: &str| v[key].as_f64();
            let _ = writeln!(
                s,
                "| {} | {} | {} | {} | {} / {} | {} | {} | {} | {} | {} |",
                v["estimator"].as_str().unwrap_or("?"),
                count(v["photons"].as_u64().unwrap_or(0)),
                count(v["segments"].as_u64().unwrap_or(0)),
                count(v["estimation_points"].as_u64().unwrap_or(0)),
                millis(num("first_frame_photosimulation_ms").unwrap_or(f64::NAN)),
                millis(num("first_frame_radiosity_ms").unwrap_or(f64::NAN)),
                frame.map_or("–".into(), millis),
                millis(num("median_photosimulation_update_ms").unwrap_or(f64::NAN)),
                millis(num("median_radiosity_ms").unwrap_or(f64::NAN)),
                num("median_recalculated_paths").map_or("–".into(), |n| format!("{n:.0}")),
                num("ray_set_bytes_per_photon").map_or("–".into(), |b| format!("{b:.0}")),
            );
        }
        let detp_100k = setups
            .iter()
            .find(|(_, v)| v["estimator"] == "detp" && v["photons"] == 100_000)
            .and_then(|(name, _)| {
                results
                    .iter()
                    .find(|r| r.id == format!("{QUASI_STATIC_GROUP}/{name}"))
            })
            .map(|r| r.median_ns / 1e6);
        let paper: Vec<String> = PAPER_FRAMES
            .iter()
            .map(|(p, t)| format!("{} photons {:.2} s", count(*p), t))
            .collect();
        let _ = writeln!(
            s,
            "\nThe paper, DETP with ray cache and sorted queries on its tree scene: {} per frame (tables 2.6, 2.7; a 2003 PC). Target: a DETP frame at 100,000 photons within {TARGET_FRAME_MS:.0} ms{}.",
            paper.join(", "),
            detp_100k.map_or(String::new(), |ms| format!(
                ": measured {ms:.1} ms, {}",
                if ms <= TARGET_FRAME_MS {
                    format!("met with {:.1}× to spare", TARGET_FRAME_MS / ms)
                } else {
                    format!("missed by {:.1}×", ms / TARGET_FRAME_MS)
                }
            ))
        );
    }
    let detp: Vec<&Measurement> = results
        .iter()
        .filter(|r| {
            r.id.starts_with("detp_r") || r.id.starts_with("leaf_r") || r.id.starts_with("mobile_")
        })
        // Criterion times brute force only at the default size; at DETP_BENCH_FULL's it runs once outside criterion.
        .filter(|r| !r.id.contains("brute_force"))
        .collect();
    if !detp.is_empty() {
        let _ = writeln!(
            s,
            "\n## DETP speed-ups (lustre-density, sections 2.6–2.8)\n"
        );
        let _ = writeln!(
            s,
            "The full DETP estimate (`DiscSet::accumulate` over every segment) on the Cornell box \
             subdivided as the `detp` bench's documentation says, for each acceleration and \
             pre-intersection test (`detp_r<radius>/<acceleration>/<pre-test>`), the disc-index leaf \
             sweep per radius in the form of table 2.2 (`leaf_r<radius>/leaf_<n>`), and the mobile \
             object's discs moved each frame (`mobile_<n>discs/...`). Written by `cargo xtask bench detp`; \
             `DETP_BENCH_FULL=1` uses the paper-sized setting (0.05 m edges, 23,979 discs, 100,000 photons, \
             262,574 segments), where brute force runs once outside criterion and prints its time; \
             brute-force rows are left out. Size of these rows: {}. Machine: {machine}, CPU only.\n",
            if full {
                "the paper-sized setting (`DETP_BENCH_FULL=1`)"
            } else {
                "the bench's small default (no `DETP_BENCH_FULL`)"
            }
        );
        let _ = writeln!(s, "| benchmark | median |");
        let _ = writeln!(s, "|---|---:|");
        for r in detp {
            let _ = writeln!(s, "| {} | {} |", r.id, millis(r.median_ns / 1e6));
        }
    }
    Ok(s)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sections_are_found_with_their_markers() {
        let doc = "# B\n<!-- note -->\n<!-- a:start -->\nA\n<!-- a:end -->\nx\n<!-- b:start -->B<!-- b:end -->\n<!-- c:start --> unterminated";
        assert_eq!(
            sections(doc),
            vec![
                "<!-- a:start -->\nA\n<!-- a:end -->",
                "<!-- b:start -->B<!-- b:end -->"
            ]
        );
        assert!(sections("").is_empty());
    }

    #[test]
    fn splat_tables_name_the_adapter_rows_and_target() {
        let setup = |name: &str, splats: u64| SplatSetup {
            name: name.to_owned(),
            adapter: "llvmpipe".to_owned(),
            software: true,
            hdr_format: "Rgba32Float".to_owned(),
            width: 640,
            height: 480,
            kernel_c: 4.0,
            emitted: 250_000,
            hit_records: splats,
            splats,
            cpu_busy: Some((0.5, 0.5)),
        };
        let measurement = |id: &str, ms: f64| Measurement {
            id: format!("{SPLAT_GROUP}/{id}"),
            median_ns: ms * 1e6,
            elements: None,
        };
        let results = [
            measurement("full-250k/surface-id/frame", 2000.0),
            measurement("full-250k/splats", 1000.0),
        ];
        let mut s = String::new();
        splat_tables(&mut s, &results, &[setup("full-250k", 500_000)]);
        assert!(s.contains("Adapter: llvmpipe."), "{s}");
        // No stencil result: a dash; 500k splats in 1 s.
        assert!(
            s.contains(
                "| full-250k | 4 | 250k | 500k | 2000 ms | – | 1000 ms | 500 k | 50% / 50% |"
            ),
            "{s}"
        );
        assert!(
            s.contains(
                "Not measured: full-1M, full-250k-c16, optimised-250k, optimised-1M, \
                 optimised-250k-c16."
            ),
            "{s}"
        );
        assert!(
            s.contains("| Simple | 3 | 0.5M | 2.15 | no such scene in Lustre |"),
            "{s}"
        );
        assert!(
            s.contains("Software driver: 2000 ms per 1M splats") && s.contains("missed by 8.0×"),
            "{s}"
        );
        // The paper tables state our C.
        assert!(
            s.contains("`full-250k`: 250k photons emitted, 500k hit records | 4 | 500k | 2.00 |"),
            "{s}"
        );
        let mut empty = String::new();
        splat_tables(&mut empty, &results, &[]);
        assert!(empty.is_empty());
    }

    #[test]
    fn only_results_written_since_the_run_began_count() {
        let dir = std::env::temp_dir().join(format!("lustre-bench-since-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let write = |group: &str| {
            let new = dir.join(group).join("new");
            std::fs::create_dir_all(&new).unwrap();
            std::fs::write(
                new.join("benchmark.json"),
                format!(r#"{{"full_id": "{group}", "throughput": null}}"#),
            )
            .unwrap();
            std::fs::write(
                new.join("estimates.json"),
                r#"{"median": {"point_estimate": 1000.0}}"#,
            )
            .unwrap();
        };
        write("old");
        std::thread::sleep(std::time::Duration::from_millis(50));
        let started = std::time::SystemTime::now();
        std::thread::sleep(std::time::Duration::from_millis(50));
        write("fresh");
        let mut results = Vec::new();
        collect(&dir, &mut results, started).unwrap();
        let ids: Vec<&str> = results.iter().map(|r| r.id.as_str()).collect();
        assert_eq!(ids, ["fresh"]);
        let mut all = Vec::new();
        collect(&dir, &mut all, std::time::UNIX_EPOCH).unwrap();
        assert_eq!(all.len(), 2);
        // Density sections name the machine and the size.
        let text = density_tables(
            &[Measurement {
                id: "detp_r0.05/disc_index/none".into(),
                median_ns: 1e6,
                elements: None,
            }],
            &dir,
            started,
            "Test CPU, 2 cores available",
            false,
        )
        .unwrap();
        assert!(
            text.contains("Size of these rows: the bench's small default")
                && text.contains("Machine: Test CPU, 2 cores available, CPU only."),
            "{text}"
        );
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn replace_section_keeps_the_rest() {
        let doc =
            "# Benchmarks\n\ntext\n<!-- converge:start -->\nold\n<!-- converge:end -->\ntail\n";
        assert_eq!(
            replace_section(doc, "converge", "new\n"),
            "# Benchmarks\n\ntext\n<!-- converge:start -->\nnew\n<!-- converge:end -->\ntail\n"
        );
        // Missing markers: appended after a blank line.
        assert_eq!(
            replace_section("# B\ntext", "converge", "t"),
            "# B\ntext\n\n<!-- converge:start -->\nt\n<!-- converge:end -->\n"
        );
        assert_eq!(
            replace_section("", "converge", "t\n"),
            "<!-- converge:start -->\nt\n<!-- converge:end -->\n"
        );
        // Replacing twice is the same as once.
        let once = replace_section("# B\n", "converge", "t\n");
        assert_eq!(replace_section(&once, "converge", "t\n"), once);
    }
}
