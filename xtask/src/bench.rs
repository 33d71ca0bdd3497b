//! `cargo xtask bench`: runs the criterion benches and writes BENCHMARKS.md
//! from their medians.

use std::fmt::Write as _;
use std::path::Path;

use anyhow::Context;
use serde_json::Value;

/// The criterion benches to run: (package, bench target).
const BENCHES: &[(&str, &str)] = &[
    ("lustre-geometry", "bvh"),
    ("lustre-brdf", "brdf"),
    ("lustre-photon", "trace"),
];

/// One criterion result.
struct Measurement {
    id: String,
    median_ns: f64,
    elements: Option<f64>,
}

/// Runs every bench (or only those whose target matches `filter`) and rewrites BENCHMARKS.md.
pub fn run(filter: Option<&str>) -> anyhow::Result<()> {
    for (package, bench) in BENCHES {
        if filter.is_some_and(|f| !bench.contains(f)) {
            continue;
        }
        crate::ci::cargo(&["bench", "-p", package, "--bench", bench, "--", "--noplot"])?;
    }
    let root = crate::workspace_root();
    let mut results = Vec::new();
    collect(&root.join("target/criterion"), &mut results)?;
    results.sort_by(|a, b| a.id.cmp(&b.id));
    let mut text = render(&results);
    let path = root.join("BENCHMARKS.md");
    // Keep the marker-delimited sections other subcommands own (`converge`).
    let previous = std::fs::read_to_string(&path).unwrap_or_default();
    for section in sections(&previous) {
        text.push('\n');
        text.push_str(section);
        text.push('\n');
    }
    let tmp = path.with_extension("md.tmp");
    std::fs::write(&tmp, text).with_context(|| format!("cannot write {}", tmp.display()))?;
    std::fs::rename(&tmp, &path).with_context(|| format!("cannot write {}", path.display()))?;
    println!("xtask: wrote {}", path.display());
    Ok(())
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

/// Finds every `new/benchmark.json` + `new/estimates.json` pair under `dir`.
fn collect(dir: &Path, out: &mut Vec<Measurement>) -> anyhow::Result<()> {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return Ok(());
    };
    for entry in entries {
        let path = entry?.path();
        if !path.is_dir() {
            continue;
        }
        if path.file_name().is_some_and(|n| n == "new") {
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
            collect(&path, out)?;
        }
    }
    Ok(())
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
        "Machine: {}. GPU adapter: none used by these benches (CPU only).\n",
        machine()
    );
    let _ = writeln!(s, "## BVH closest hit (lustre-geometry, obvhs CWBVH)\n");
    let _ = writeln!(
        s,
        "65,536 rays per batch, rayon-parallel: coherent rays are one primary ray per pixel of a \
         256×256 image; incoherent rays start at random points inside the scene's bounds in \
         uniformly random directions. `spheres-516k` is 64 UV spheres of 8,064 triangles \
         (516,096 triangles). `coherent-obvhs-baseline` traces the same coherent rays with obvhs \
         alone (its own triangle test, returning only the distance): the ratio to `coherent` is \
         what our hit records (barycentrics, normals, UVs, surface and material ids) cost.\n"
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
