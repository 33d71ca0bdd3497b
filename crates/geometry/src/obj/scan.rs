//! Line-by-line validation of an OBJ file, which rewrites the statements that
//! matter into a text tobj cannot fail or panic on.

use std::collections::{BTreeMap, HashMap};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use glam::Vec3;

use super::{mtl, parse_error, parse_number, read_text, split_keyword};
use crate::meshing::triangulate_polygon;
use crate::{GeometryError, Material, Result};

/// The result of scanning an OBJ file.
pub(super) struct ScannedObj {
    /// The statements for tobj: one synthetic `mtllib`, `o`, `v`, `vt`, `vn`,
    /// `f` (absolute indices), `usemtl INDEX`.
    pub text: String,
    /// Every material of every library, a redefined name replacing the earlier one in place.
    pub materials: Vec<Material>,
    /// Number of `f` statements.
    pub faces: usize,
}

/// A line of the rewritten text.
enum Out {
    Text(String),
    /// A face: its tobj model (segment) and its vertices as 1-based
    /// `[v, vt, vn]`, 0 for an absent `vt`/`vn`.
    Face {
        segment: usize,
        vertices: Vec<[usize; 3]>,
        line: usize,
    },
}

/// Which attributes the faces of one tobj model carry.
#[derive(Default)]
struct Segment {
    first_line: usize,
    object: String,
    with_vt: bool,
    without_vt: bool,
    with_vn: bool,
    without_vn: bool,
}

/// Validates an OBJ text and the libraries it names, line by line.
pub(super) fn scan_obj(
    path: &Path,
    text: &str,
    stem: &str,
    warnings: &mut Vec<String>,
) -> Result<ScannedObj> {
    let dir = path.parent().unwrap_or(Path::new(""));
    let err = |line: usize, message: String| parse_error(path, Some(line), message);
    // Counts of `v`, `vt`, `vn` so far.
    let mut counts = [0usize; 3];
    // The `v` positions, for triangulating polygons.
    let mut positions: Vec<Vec3> = Vec::new();
    const KINDS: [&str; 3] = [
        "vertices (`v`)",
        "texture coordinates (`vt`)",
        "normals (`vn`)",
    ];
    let mut out: Vec<Out> = Vec::new();
    let mut materials: Vec<Material> = Vec::new();
    let mut material_index: HashMap<String, usize> = HashMap::new();
    // Material names `usemtl` gave that no library defines (warned once each).
    let mut unknown: std::collections::HashSet<String> = std::collections::HashSet::new();
    // tobj starts a new model at `o`/`g`, and at `usemtl` of another material,
    // when the current one has faces; the segments follow the same rule.
    let mut segments = vec![Segment {
        object: stem.to_owned(),
        ..Default::default()
    }];
    let mut segment_has_faces = false;
    let mut current_material: Option<usize> = None;
    let mut object = stem.to_owned();
    let mut faces = 0;
    let mut ignored: BTreeMap<String, (usize, usize)> = BTreeMap::new();

    for (i, raw) in text.lines().enumerate() {
        let n = i + 1;
        let line = raw.trim();
        let (keyword, rest) = split_keyword(line);
        // Numeric statements tolerate a trailing `# comment`.
        let numbers = || rest.split_whitespace().take_while(|t| !t.starts_with('#'));
        match keyword {
            "" => {}
            k if k.starts_with('#') => {}
            "v" => {
                let values = numbers()
                    .map(|t| parse_number(t, path, n, "vertex position"))
                    .collect::<Result<Vec<f32>>>()?;
                let mut p = match values.len() {
                    3 | 4 | 6 => [values[0], values[1], values[2]],
                    count => {
                        return Err(err(
                            n,
                            format!(
                                "`v` takes x y z, optionally w or an RGB colour; found {count} numbers"
                            ),
                        ));
                    }
                };
                if values.len() == 4 {
                    let w = values[3];
                    if w == 0.0 {
                        return Err(err(n, "`v` has w = 0".into()));
                    }
                    p = p.map(|c| c / w);
                    if p.iter().any(|c| !c.is_finite()) {
                        return Err(err(n, "`v` divided by w is not finite".into()));
                    }
                }
                counts[0] += 1;
                positions.push(Vec3::from(p));
                out.push(Out::Text(format!("v {} {} {}", p[0], p[1], p[2])));
            }
            "vt" => {
                let values = numbers()
                    .map(|t| parse_number(t, path, n, "texture coordinate"))
                    .collect::<Result<Vec<f32>>>()?;
                if !(1..=3).contains(&values.len()) {
                    return Err(err(
                        n,
                        format!("`vt` takes 1 to 3 numbers; found {}", values.len()),
                    ));
                }
                counts[1] += 1;
                let v = values.get(1).copied().unwrap_or(0.0);
                out.push(Out::Text(format!("vt {} {v}", values[0])));
            }
            "vn" => {
                let values = numbers()
                    .map(|t| parse_number(t, path, n, "normal"))
                    .collect::<Result<Vec<f32>>>()?;
                if values.len() != 3 {
                    return Err(err(
                        n,
                        format!("`vn` takes 3 numbers; found {}", values.len()),
                    ));
                }
                counts[2] += 1;
                out.push(Out::Text(format!(
                    "vn {} {} {}",
                    values[0], values[1], values[2]
                )));
            }
            "f" => {
                let mut vertices = Vec::new();
                for token in numbers() {
                    let parts: Vec<&str> = token.split('/').collect();
                    if parts.len() > 3 || parts[0].is_empty() {
                        return Err(err(
                            n,
                            format!(
                                "face vertex `{token}` is not `v`, `v/vt`, `v//vn` or `v/vt/vn`"
                            ),
                        ));
                    }
                    let mut vertex = [0usize; 3];
                    for (k, part) in parts.iter().enumerate() {
                        if part.is_empty() {
                            continue;
                        }
                        let index: i64 = part.parse().map_err(|_| {
                            err(
                                n,
                                format!("face vertex `{token}`: `{part}` is not an integer"),
                            )
                        })?;
                        let count = counts[k];
                        let kind = KINDS[k];
                        vertex[k] = if index == 0 {
                            return Err(err(
                                n,
                                format!("face vertex `{token}`: index 0 (OBJ indices start at 1)"),
                            ));
                        } else if index > 0 {
                            if index as u64 > count as u64 {
                                return Err(err(
                                    n,
                                    format!(
                                        "face vertex `{token}`: index {index} is out of range: {count} {kind} so far"
                                    ),
                                ));
                            }
                            index as usize
                        } else {
                            if index.unsigned_abs() > count as u64 {
                                return Err(err(
                                    n,
                                    format!(
                                        "face vertex `{token}`: relative index {index} reaches before the first of the {count} {kind} so far"
                                    ),
                                ));
                            }
                            count - index.unsigned_abs() as usize + 1
                        };
                    }
                    vertices.push(vertex);
                }
                if vertices.len() < 3 {
                    return Err(err(
                        n,
                        format!("a face needs at least 3 vertices; found {}", vertices.len()),
                    ));
                }
                if !segment_has_faces {
                    segment_has_faces = true;
                    let segment = segments.last_mut().unwrap();
                    segment.first_line = n;
                    segment.object = object.clone();
                }
                let segment = segments.last_mut().unwrap();
                for v in &vertices {
                    segment.with_vt |= v[1] != 0;
                    segment.without_vt |= v[1] == 0;
                    segment.with_vn |= v[2] != 0;
                    segment.without_vn |= v[2] == 0;
                }
                faces += 1;
                out.push(Out::Face {
                    segment: segments.len() - 1,
                    vertices,
                    line: n,
                });
            }
            "o" | "g" => {
                if segment_has_faces {
                    segments.push(Segment::default());
                    segment_has_faces = false;
                }
                object = if rest.is_empty() {
                    stem.to_owned()
                } else {
                    rest.to_owned()
                };
                out.push(Out::Text(format!("o {object}")));
            }
            "mtllib" => {
                if rest.is_empty() {
                    return Err(err(n, "`mtllib` names no file".into()));
                }
                let whole = dir.join(rest);
                let files: Vec<PathBuf> = if whole.is_file() || !rest.contains(char::is_whitespace)
                {
                    vec![whole]
                } else {
                    rest.split_whitespace().map(|name| dir.join(name)).collect()
                };
                for file in files {
                    // A library that cannot be read is a warning: its
                    // materials' faces take the default material (as other
                    // viewers show such a model).
                    let text = match read_text(&file) {
                        Ok(text) => text,
                        Err(GeometryError::Io { source, .. }) => {
                            warnings.push(format!(
                                "{}:{n}: material library `{}` cannot be read ({source}); its materials are drawn with the default material",
                                path.display(),
                                file.display()
                            ));
                            continue;
                        }
                        Err(other) => return Err(other),
                    };
                    for material in mtl::parse_library(&file, &text, warnings)? {
                        match material_index.get(&material.name) {
                            Some(&m) => {
                                warnings.push(format!(
                                    "{}:{n}: material `{}` is defined again in `{}`; the later definition is used",
                                    path.display(),
                                    material.name,
                                    file.display()
                                ));
                                materials[m] = material;
                            }
                            None => {
                                material_index.insert(material.name.clone(), materials.len());
                                materials.push(material);
                            }
                        }
                    }
                }
            }
            "usemtl" => {
                if rest.is_empty() {
                    return Err(err(n, "`usemtl` names no material".into()));
                }
                let m = match material_index.get(rest) {
                    Some(&m) => m,
                    None => {
                        if unknown.insert(rest.to_owned()) {
                            warnings.push(format!(
                                "{}:{n}: unknown material `{rest}` (no material library loaded before this line defines it); drawn with the default material",
                                path.display()
                            ));
                        }
                        match material_index.get(super::DEFAULT_MATERIAL_NAME) {
                            Some(&d) => d,
                            None => {
                                materials.push(super::fallback_material());
                                material_index.insert(
                                    super::DEFAULT_MATERIAL_NAME.to_owned(),
                                    materials.len() - 1,
                                );
                                materials.len() - 1
                            }
                        }
                    }
                };
                if current_material != Some(m) && segment_has_faces {
                    segments.push(Segment::default());
                    segment_has_faces = false;
                }
                current_material = Some(m);
                out.push(Out::Text(format!("usemtl {m}")));
            }
            "s" => {}
            other => {
                let entry = ignored.entry(other.to_owned()).or_insert((n, 0));
                entry.1 += 1;
            }
        }
    }

    for (keyword, (line, count)) in ignored {
        warnings.push(format!(
            "{}:{line}: ignored {count} `{keyword}` statement{}",
            path.display(),
            if count == 1 { "" } else { "s" }
        ));
    }
    // Attributes present on only some faces of a model cannot be aligned by
    // tobj's single-index loader: drop them for the whole model.
    let mut keep = Vec::with_capacity(segments.len());
    for segment in &segments {
        let keep_vt = !(segment.with_vt && segment.without_vt);
        let keep_vn = !(segment.with_vn && segment.without_vn);
        for (kept, what) in [(keep_vt, "texture coordinates"), (keep_vn, "normals")] {
            if !kept {
                warnings.push(format!(
                    "{}:{}: object `{}`: some faces have {what} and some do not; {what} dropped for this mesh",
                    path.display(),
                    segment.first_line,
                    segment.object
                ));
            }
        }
        keep.push((keep_vt, keep_vn));
    }

    let mut text = String::with_capacity(text.len() + 64);
    text.push_str("mtllib lustre.mtl\n");
    let _ = writeln!(text, "o {stem}");
    for line in out {
        match line {
            Out::Text(t) => {
                text.push_str(&t);
                text.push('\n');
            }
            Out::Face {
                segment,
                vertices,
                line,
            } => {
                let (keep_vt, keep_vn) = keep[segment];
                for triangle in triangulate_face(&vertices, &positions, path, line, warnings) {
                    text.push('f');
                    for [v, vt, vn] in triangle.map(|k| vertices[k]) {
                        let vt = if keep_vt { vt } else { 0 };
                        let vn = if keep_vn { vn } else { 0 };
                        let _ = match (vt, vn) {
                            (0, 0) => write!(text, " {v}"),
                            (vt, 0) => write!(text, " {v}/{vt}"),
                            (0, vn) => write!(text, " {v}//{vn}"),
                            (vt, vn) => write!(text, " {v}/{vt}/{vn}"),
                        };
                    }
                    text.push('\n');
                }
            }
        }
    }
    Ok(ScannedObj {
        text,
        materials,
        faces,
    })
}

/// Triangles of a face as corner indices into `vertices`: a triangle as it
/// is; a convex polygon as a fan around its first corner (as every OBJ
/// reader does); a concave one by constrained Delaunay triangulation of its
/// plane, so that no triangle leaves the outline. A polygon that is not
/// simple and planar falls back to the fan, with a warning.
fn triangulate_face(
    vertices: &[[usize; 3]],
    positions: &[Vec3],
    path: &Path,
    line: usize,
    warnings: &mut Vec<String>,
) -> Vec<[usize; 3]> {
    let n = vertices.len();
    let fan = || (1..n - 1).map(|k| [0, k, k + 1]).collect();
    let outline: Vec<Vec3> = vertices.iter().map(|v| positions[v[0] - 1]).collect();
    if n == 3 || is_convex(&outline) {
        return fan();
    }
    let triangulated = triangulate_polygon(&outline, &[])
        .ok()
        .and_then(|(points, triangles)| {
            // The triangulation returns input points (minus repeats); map them back to corners.
            let corner = |p: Vec3| outline.iter().position(|&q| q == p);
            triangles
                .iter()
                .map(|t| {
                    Some([
                        corner(points[t[0] as usize])?,
                        corner(points[t[1] as usize])?,
                        corner(points[t[2] as usize])?,
                    ])
                })
                .collect::<Option<Vec<_>>>()
        });
    match triangulated {
        // A simple polygon of n corners has n - 2 triangles; fewer means
        // repeated or collinear corners, whose fan triangles are dropped as
        // degenerate and counted instead.
        Some(triangles) if triangles.len() == n - 2 => triangles,
        Some(_) => fan(),
        None => {
            warnings.push(format!(
                "{}:{line}: face is not a simple planar polygon; triangulated as a fan",
                path.display()
            ));
            fan()
        }
    }
}

/// Whether a polygon turns the same way at every corner about its Newell
/// normal (collinear corners allowed), so that its fan stays inside it.
fn is_convex(outline: &[Vec3]) -> bool {
    let normal = crate::meshing::newell_normal(outline);
    let n = outline.len();
    (0..n).all(|i| {
        let (a, b, c) = (outline[i], outline[(i + 1) % n], outline[(i + 2) % n]);
        (b - a).cross(c - b).dot(normal) >= 0.0
    })
}
