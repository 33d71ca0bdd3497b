//! `cargo xtask bench embree`: our BVH against Embree on the same triangles
//! and the same rays, one thread each, in one run.
//!
//! Runs the example `embree_compare` of lustre-geometry in release mode (it
//! writes the sphere grid's 516,096 triangles, one million coherent and one
//! million incoherent rays, our hits and our times), then
//! `tools/embree/embree_bench.py` in `.bench-venv` (created with
//! `python3 -m venv` and `pip install embreex==`[`EMBREEX_VERSION`] when
//! missing), which traces the same files with Embree. Checks that both find
//! the same hits and returns the BENCHMARKS.md section with rays per second
//! and the ratios.

use std::fmt::Write as _;
use std::path::Path;
use std::process::Command;

use anyhow::{Context, Result, ensure};
use serde_json::Value;

use crate::venv::{Venv, checked};

/// The embreex release (Embree 4.4.0 inside) the comparison is made with.
pub const EMBREEX_VERSION: &str = "4.4.0.post1";

/// `.bench-venv` with embreex [`EMBREEX_VERSION`].
const BENCH_VENV: Venv = Venv {
    dir: ".bench-venv",
    package: "embreex",
    version: EMBREEX_VERSION,
    probe: "import embreex.rtcore_scene; from importlib.metadata import version; print(version('embreex'))",
    user: "bench",
};

/// Name of the BENCHMARKS.md section this writes.
pub const SECTION: &str = "embree";

/// Timed passes over each ray set, on each side, per round.
const RUNS: usize = 3;

/// Rounds of our side then Embree's; every figure is the median over all rounds' passes, so
/// that a slow spell of a shared machine falls on both sides.
const ROUNDS: usize = 3;

/// Relative distance tolerance, `|t_ours - t_embree| <= TOLERANCE * max(1, t)`, for two hits to agree.
const TOLERANCE: f32 = 1e-5;

/// Reads a file of little-endian 32-bit words.
fn read_words(path: &Path) -> Result<Vec<[u8; 4]>> {
    let bytes = std::fs::read(path).with_context(|| format!("cannot read {}", path.display()))?;
    ensure!(
        bytes.len() % 4 == 0,
        "{} is not a whole number of 32-bit words",
        path.display()
    );
    Ok(bytes
        .chunks_exact(4)
        .map(|c| [c[0], c[1], c[2], c[3]])
        .collect())
}

/// Reads a JSON file.
fn read_json(path: &Path) -> Result<Value> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))?;
    serde_json::from_str(&text).with_context(|| format!("{} is not JSON", path.display()))
}

/// The median of a JSON list of numbers (the mean of the middle two for an even count).
fn median(list: &Value) -> Result<f64> {
    let v: Vec<f64> = list
        .as_array()
        .context("not a list of times")?
        .iter()
        .filter_map(Value::as_f64)
        .collect();
    ensure!(!v.is_empty(), "no times");
    Ok(crate::bench::median(v))
}

/// Our query `key`'s rays a second over Embree's on the ray set `set`, each
/// round's medians against each other (a round's two sides run back to back,
/// so a slow spell of a shared machine falls on both more often than across
/// rounds): the rounds' ratios, lowest to highest, as `a, b, c`.
fn round_ratios(ours: &[Value], embree: &[Value], set: &str, key: &str) -> Result<String> {
    let mut ratios = ours
        .iter()
        .zip(embree)
        .map(|(o, e)| Ok(median(&e["sets"][set]["wall_ns"])? / median(&o["sets"][set][key])?))
        .collect::<Result<Vec<f64>>>()?;
    ratios.sort_by(f64::total_cmp);
    Ok(ratios
        .iter()
        .map(|r| format!("{r:.2}"))
        .collect::<Vec<_>>()
        .join(", "))
}

/// The first of several runs' JSON results with every list of times under
/// `sets` replaced by the concatenation of all runs' lists, and `build_ms` by
/// its median.
fn merge(rounds: &[Value]) -> Value {
    let Some(first) = rounds.first() else {
        return Value::Null;
    };
    let mut out = first.clone();
    let builds: Vec<Value> = rounds.iter().map(|r| r["build_ms"].clone()).collect();
    if let Ok(m) = median(&Value::Array(builds)) {
        out["build_ms"] = m.into();
    }
    if let Some(sets) = out["sets"].as_object_mut() {
        for (name, set) in sets.iter_mut() {
            let Some(fields) = set.as_object_mut() else {
                continue;
            };
            for (key, value) in fields.iter_mut() {
                if value.is_array() {
                    *value = Value::Array(
                        rounds
                            .iter()
                            .filter_map(|r| r["sets"][name][key].as_array())
                            .flatten()
                            .cloned()
                            .collect(),
                    );
                }
            }
        }
    }
    out
}

/// How our hits and Embree's compare on one ray set.
#[derive(Debug, Default, PartialEq)]
pub struct Agreement {
    /// Rays in the set.
    pub rays: usize,
    /// Rays that hit something in ours / in Embree's.
    pub hits: (usize, usize),
    /// Rays both hit or both miss.
    pub same_hit_or_miss: usize,
    /// Rays both hit, on the same triangle.
    pub same_triangle: usize,
    /// Rays both hit, at distances within [`TOLERANCE`] (on the same triangle or not: a ray through a shared edge may take either).
    pub same_distance: usize,
}

/// Compares two sets of closest hits (distance, triangle id; `-1` for a miss).
pub fn agreement(ours: (&[f32], &[i32]), embree: (&[f32], &[i32])) -> Agreement {
    let mut a = Agreement {
        rays: ours.0.len(),
        ..Agreement::default()
    };
    for i in 0..ours.0.len().min(embree.0.len()) {
        let (t0, id0, t1, id1) = (ours.0[i], ours.1[i], embree.0[i], embree.1[i]);
        let (hit0, hit1) = (id0 >= 0, id1 >= 0);
        a.hits.0 += usize::from(hit0);
        a.hits.1 += usize::from(hit1);
        if hit0 != hit1 {
            continue;
        }
        a.same_hit_or_miss += 1;
        if hit0 {
            a.same_triangle += usize::from(id0 == id1);
            a.same_distance += usize::from((t0 - t1).abs() <= TOLERANCE * t0.abs().max(1.0));
        }
    }
    a
}

/// Distances and ids of one side's hits on one set.
fn hits(dir: &Path, set: &str, side: &str) -> Result<(Vec<f32>, Vec<i32>)> {
    let t = read_words(&dir.join(format!("{set}.{side}.t.f32")))?
        .into_iter()
        .map(f32::from_le_bytes)
        .collect();
    let id = read_words(&dir.join(format!("{set}.{side}.id.i32")))?
        .into_iter()
        .map(i32::from_le_bytes)
        .collect();
    Ok((t, id))
}

/// Runs both sides and returns the BENCHMARKS.md section's body.
pub fn run() -> Result<String> {
    let root = crate::workspace_root();
    let python = BENCH_VENV.ensure(&root)?;
    let load = std::fs::read_to_string("/proc/loadavg")
        .ok()
        .and_then(|l| l.split_whitespace().next().map(str::to_owned))
        .unwrap_or_else(|| "?".into());
    let dir = root.join("target").join("tmp").join("embree-bench");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).with_context(|| format!("creating {}", dir.display()))?;
    let dir_arg = dir.to_str().context("non-UTF-8 path")?;
    let runs = RUNS.to_string();
    let (mut ours_rounds, mut embree_rounds) = (Vec::new(), Vec::new());
    for _ in 0..ROUNDS {
        crate::ci::cargo(&[
            "run",
            "--release",
            "-p",
            "lustre-geometry",
            "--example",
            "embree_compare",
            "--",
            dir_arg,
            &runs,
        ])?;
        checked(
            Command::new(&python)
                .arg(root.join("tools").join("embree").join("embree_bench.py"))
                .args([dir_arg, &runs]),
        )
        .context("the Embree side (tools/embree/embree_bench.py)")?;
        ours_rounds.push(read_json(&dir.join("ours.json"))?);
        embree_rounds.push(read_json(&dir.join("embree.json"))?);
    }
    let (ours, embree) = (merge(&ours_rounds), merge(&embree_rounds));
    let mut s = String::new();
    let _ = writeln!(s, "## BVH against Embree (closest hit, one thread)\n");
    let _ = writeln!(
        s,
        "Written by `cargo xtask bench embree`. The same {} triangles (the `spheres-516k` grid) and \
         the same rays, traced by our BVH (example `embree_compare` of lustre-geometry, release \
         mode) and by Embree {} through embreex {} (`tools/embree/embree_bench.py`, numpy {}, \
         Python {}), one thread each, one after the other in one run ({} rounds of ours then Embree's). Coherent: one primary ray per \
         pixel of a 1000×1000 image; incoherent: one million rays from random points inside the \
         grid's bounds in uniformly random directions; `t` in `[0, ∞)`. Each figure is the median \
         of {} passes over all rays of the set ({RUNS} per round), wall time of the query calls only (rays and arrays \
         prepared before, BVHs built before); *each round*: the ratio of one round's medians \
         (its {RUNS} passes on each side), lowest to highest. Ours: `Bvh::closest_hit` (the full hit record: \
         position, normals, UVs, surface, material) and `Bvh::closest_hit_lean` (distance, triangle \
         id, barycentrics), called ray by ray in a loop, on the eight-wide BVH; *before*: the full \
         record as `closest_hit` made it until the eight-wide BVH, rebuilt in the example from \
         obvhs' CWBVH (`build_cwbvh_from_tris`, medium settings), our triangle test and \
         `Bvh::hit_record`. Embree: `EmbreeScene.run(origins, \
         directions, output=1)` (not robust), which calls `rtcIntersect1` ray by ray on the calling \
         thread and returns primID, distance, barycentrics and geometric normal; its scene is built \
         with the process pinned to one CPU (so TBB starts one thread), the pin is lifted for \
         tracing (ours is not pinned either). Machine: {}, CPU only; load average {load} when the \
         run began (the machine may be shared).\n",
        ours["triangles"],
        embree["embree"].as_str().unwrap_or("?"),
        embree["embreex"].as_str().unwrap_or("?"),
        embree["numpy"].as_str().unwrap_or("?"),
        embree["python"].as_str().unwrap_or("?"),
        ROUNDS,
        RUNS * ROUNDS,
        crate::bench::machine(),
    );
    let _ = writeln!(
        s,
        "| rays | before | ours, full record | ours, lean | Embree | before / Embree | full / Embree | lean / Embree | full / Embree, each round | lean / Embree, each round | Embree CPU / wall |"
    );
    let _ = writeln!(s, "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|");
    let mut checks = String::new();
    let mut floors = Vec::new();
    for set in ["coherent", "incoherent"] {
        let (o, e) = (&ours["sets"][set], &embree["sets"][set]);
        let n = o["rays"].as_f64().context("ours.json: rays")?;
        let per_s = |ns: f64| n / (ns * 1e-9);
        let full = per_s(median(&o["full_ns"])?);
        let lean = per_s(median(&o["lean_ns"])?);
        let before = per_s(median(&o["cwbvh_full_ns"])?);
        let theirs = per_s(median(&e["wall_ns"])?);
        let sum = |v: &Value| {
            v.as_array()
                .map_or(0.0, |a| a.iter().filter_map(Value::as_f64).sum::<f64>())
        };
        let cpu = sum(&e["cpu_ns"]) / sum(&e["wall_ns"]);
        let full_rounds = round_ratios(&ours_rounds, &embree_rounds, set, "full_ns")?;
        let lean_rounds = round_ratios(&ours_rounds, &embree_rounds, set, "lean_ns")?;
        let _ = writeln!(
            s,
            "| {set} | {:.2} M/s | {:.2} M/s | {:.2} M/s | {:.2} M/s | {:.2} | {:.2} | {:.2} | {full_rounds} | {lean_rounds} | {cpu:.2} |",
            before / 1e6,
            full / 1e6,
            lean / 1e6,
            theirs / 1e6,
            before / theirs,
            full / theirs,
            lean / theirs
        );
        floors.push(format!(
            "{set} {:.0} ns",
            median(&e["miss_all_wall_ns"])? / n
        ));
        let (ours_hits, embree_hits) = (hits(&dir, set, "ours")?, hits(&dir, set, "embree")?);
        ensure!(
            ours_hits.0.len() == n as usize && embree_hits.0.len() == n as usize,
            "{set}: {} of our hits and {} of Embree's for {n} rays",
            ours_hits.0.len(),
            embree_hits.0.len()
        );
        let a = agreement(
            (&ours_hits.0, &ours_hits.1),
            (&embree_hits.0, &embree_hits.1),
        );
        let _ = writeln!(
            checks,
            "| {set} | {} | {} | {} | {} | {} | {} |",
            a.rays, a.hits.0, a.hits.1, a.same_hit_or_miss, a.same_triangle, a.same_distance
        );
    }
    let _ = writeln!(
        s,
        "\nBuilds: ours {:.0} ms (binary PLOC tree and eight-wide BVH; rayon on all cores), Embree's scene commit {:.0} ms (one CPU).",
        ours["build_ms"].as_f64().unwrap_or(f64::NAN),
        embree["build_ms"].as_f64().unwrap_or(f64::NAN)
    );
    let _ = writeln!(
        s,
        "\nEmbree's cost per ray outside its traversal (the same calls on rays that start far away \
         and point away from the scene, so that they stop at the root box): {}.\n",
        floors.join(", ")
    );
    let _ = writeln!(
        s,
        "Same hits: both hit or both miss; of the rays both hit, the same triangle, and distances \
         within {TOLERANCE:e} relative (`|Δt| ≤ {TOLERANCE:e}·max(1, t)`; a ray through an edge \
         shared by two triangles may take either).\n"
    );
    let _ = writeln!(
        s,
        "| rays | rays | hits, ours | hits, Embree | same hit or miss | same triangle | same distance |"
    );
    let _ = writeln!(s, "|---|---:|---:|---:|---:|---:|---:|");
    s.push_str(&checks);
    Ok(s)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_ratios_compare_each_rounds_medians() {
        let ours = [
            serde_json::json!({"sets": {"c": {"full_ns": [40.0, 20.0, 30.0]}}}),
            serde_json::json!({"sets": {"c": {"full_ns": [10.0, 10.0, 50.0]}}}),
        ];
        let embree = [
            serde_json::json!({"sets": {"c": {"wall_ns": [15.0, 15.0, 15.0]}}}),
            serde_json::json!({"sets": {"c": {"wall_ns": [1.0, 9.0, 8.0]}}}),
        ];
        // Round 1: 15 / 30 = 0.5; round 2: 8 / 10 = 0.8.
        assert_eq!(
            round_ratios(&ours, &embree, "c", "full_ns").unwrap(),
            "0.50, 0.80"
        );
        assert!(round_ratios(&ours, &embree, "c", "lean_ns").is_err());
    }

    #[test]
    fn agreement_counts_hits_triangles_and_distances() {
        let ours_t = [1.0, 2.0, f32::INFINITY, 5.0, 3.0];
        let ours_id = [0, 1, -1, 4, 7];
        let embree_t = [1.0, 2.0 + 1e-6, 4.0, 5.1, 3.0];
        let embree_id = [0, 2, 3, 4, 7];
        let a = agreement((&ours_t, &ours_id), (&embree_t, &embree_id));
        assert_eq!(
            a,
            Agreement {
                rays: 5,
                hits: (4, 5),
                same_hit_or_miss: 4,
                same_triangle: 3,
                same_distance: 3,
            }
        );
        assert!(median(&serde_json::json!([3, 1, 2])).unwrap() == 2.0);
        assert!(median(&serde_json::json!([4, 1, 2, 3])).unwrap() == 2.5);
        assert!(median(&serde_json::json!([])).is_err());
        let merged = merge(&[
            serde_json::json!({"build_ms": 3.0, "sets": {"a": {"rays": 2, "ns": [1, 2]}}}),
            serde_json::json!({"build_ms": 1.0, "sets": {"a": {"rays": 2, "ns": [3]}}}),
            serde_json::json!({"build_ms": 2.0, "sets": {"a": {"rays": 2, "ns": []}}}),
        ]);
        assert_eq!(
            merged,
            serde_json::json!({"build_ms": 2.0, "sets": {"a": {"rays": 2, "ns": [1, 2, 3]}}})
        );
    }
}
