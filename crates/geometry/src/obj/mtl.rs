//! MTL libraries: a line scanner that keeps the line of every value, and the
//! mapping of the values to a [`MaterialModel`] (rules in [`crate::obj`]).

use std::collections::{BTreeMap, HashMap};
use std::path::{Path, PathBuf};
use std::sync::Arc;

use super::{parse_error, parse_number, read_text, split_keyword};
use crate::material::{ConductorFresnel, MicrofacetDistribution};
use crate::{GeometryError, Material, MaterialModel, Result, Rgb, Texture};

/// The materials of one MTL file.
#[derive(Debug, Clone, PartialEq)]
pub struct MtlLibrary {
    /// The materials in order of definition (a name defined twice keeps the later definition).
    pub materials: Vec<Material>,
    /// Statements ignored and questionable values, with file and line.
    pub warnings: Vec<String>,
}

/// Reads and maps the materials of an MTL file (see [`crate::obj`] for the rules).
pub fn load_mtl(path: &Path) -> Result<MtlLibrary> {
    let text = read_text(path)?;
    let mut warnings = Vec::new();
    let mut materials: Vec<Material> = Vec::new();
    let mut index: HashMap<String, usize> = HashMap::new();
    for material in parse_library(path, &text, &mut warnings)? {
        match index.get(&material.name) {
            Some(&i) => materials[i] = material,
            None => {
                index.insert(material.name.clone(), materials.len());
                materials.push(material);
            }
        }
    }
    Ok(MtlLibrary {
        materials,
        warnings,
    })
}

/// A value and the line that set it.
#[derive(Debug, Clone, Copy)]
struct At<T> {
    value: T,
    line: usize,
}

/// `lustre_fresnel` values.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum FresnelKey {
    None,
    Conductor,
}

/// A material as written, every value with its line.
#[derive(Debug, Default)]
struct RawMaterial {
    name: String,
    kd: Option<At<Rgb>>,
    ks: Option<At<Rgb>>,
    ke: Option<At<Rgb>>,
    tf: Option<At<Rgb>>,
    ns: Option<At<f32>>,
    ni: Option<At<f32>>,
    d: Option<At<f32>>,
    tr: Option<At<f32>>,
    pr: Option<At<f32>>,
    pm: Option<At<f32>>,
    illum: Option<At<u32>>,
    map_kd: Option<PathBuf>,
    map_ks: Option<PathBuf>,
    model: Option<At<String>>,
    alpha: Option<At<f32>>,
    alpha_x: Option<At<f32>>,
    alpha_y: Option<At<f32>>,
    eta: Option<At<Rgb>>,
    k: Option<At<Rgb>>,
    fresnel: Option<At<FresnelKey>>,
    blend_weight: Option<At<f32>>,
    distribution: Option<At<MicrofacetDistribution>>,
    params: BTreeMap<String, Vec<f32>>,
    param_line: Option<usize>,
}

/// The allowed range of a value.
#[derive(Debug, Clone, Copy)]
enum Range {
    /// [0, 1].
    Unit,
    /// [0, inf).
    NonNegative,
    /// (0, inf).
    Positive,
    /// Any finite value.
    Finite,
}

impl Range {
    fn contains(self, v: f32) -> bool {
        match self {
            Self::Unit => (0.0..=1.0).contains(&v),
            Self::NonNegative => v >= 0.0,
            Self::Positive => v > 0.0,
            Self::Finite => true,
        }
    }

    fn describe(self) -> &'static str {
        match self {
            Self::Unit => "in [0, 1]",
            Self::NonNegative => "at least 0",
            Self::Positive => "above 0",
            Self::Finite => "finite",
        }
    }
}

/// Where a statement is: for messages.
#[derive(Clone, Copy)]
struct Ctx<'a> {
    path: &'a Path,
    line: usize,
    material: &'a str,
    keyword: &'a str,
}

impl Ctx<'_> {
    fn error(&self, message: impl std::fmt::Display) -> GeometryError {
        parse_error(
            self.path,
            Some(self.line),
            format!("material `{}`: `{}` {message}", self.material, self.keyword),
        )
    }

    /// The numbers of the statement (a trailing `# comment` allowed), each in `range`.
    fn numbers(&self, rest: &str, range: Range) -> Result<Vec<f32>> {
        rest.split_whitespace()
            .take_while(|t| !t.starts_with('#'))
            .map(|t| {
                let v = parse_number(
                    t,
                    self.path,
                    self.line,
                    &format!("material `{}`: `{}`", self.material, self.keyword),
                )?;
                if range.contains(v) {
                    Ok(v)
                } else {
                    Err(self.error(format_args!(
                        "value {v} is out of range: must be {}",
                        range.describe()
                    )))
                }
            })
            .collect()
    }

    /// Exactly one number in `range`.
    fn number(&self, rest: &str, range: Range) -> Result<At<f32>> {
        match self.numbers(rest, range)?.as_slice() {
            [v] => Ok(At {
                value: *v,
                line: self.line,
            }),
            other => Err(self.error(format_args!("takes 1 number; found {}", other.len()))),
        }
    }

    /// One number (grey) or three, each in `range`.
    fn colour(&self, rest: &str, range: Range) -> Result<At<Rgb>> {
        if let Some(word @ ("spectral" | "xyz")) = rest.split_whitespace().next() {
            return Err(self.error(format_args!(
                "`{word}` colours are not supported; write linear RGB"
            )));
        }
        let value = match self.numbers(rest, range)?.as_slice() {
            [g] => Rgb::splat(*g),
            [r, g, b] => Rgb::new(*r, *g, *b),
            other => {
                return Err(self.error(format_args!("takes 1 or 3 numbers; found {}", other.len())));
            }
        };
        Ok(At {
            value,
            line: self.line,
        })
    }

    /// A single word.
    fn word(&self, rest: &str) -> Result<At<String>> {
        let words: Vec<&str> = rest.split_whitespace().collect();
        match words.as_slice() {
            [w] => Ok(At {
                value: (*w).to_owned(),
                line: self.line,
            }),
            other => Err(self.error(format_args!("takes one word; found {}", other.len()))),
        }
    }

    /// A texture statement: options skipped, the file resolved against `dir`;
    /// `None`, with a warning, when the file is not there (other viewers
    /// show such a model without its texture, and so does Lustre).
    fn texture(
        &self,
        dir: &Path,
        rest: &str,
        warnings: &mut Vec<String>,
    ) -> Result<Option<PathBuf>> {
        let tokens: Vec<&str> = rest.split_whitespace().collect();
        let mut i = 0;
        let mut options = Vec::new();
        while i < tokens.len() {
            let (min, max) = match tokens[i] {
                "-blendu" | "-blendv" | "-cc" | "-clamp" | "-bm" | "-boost" | "-texres"
                | "-imfchan" | "-type" => (1, 1),
                "-mm" => (2, 2),
                "-o" | "-s" | "-t" => (1, 3),
                _ => break,
            };
            options.push(tokens[i]);
            i += 1;
            let mut taken = 0;
            while taken < max && i < tokens.len() {
                let numeric = min < max; // -o/-s/-t take 1 to 3 numbers
                if numeric && tokens[i].parse::<f32>().is_err() {
                    break;
                }
                i += 1;
                taken += 1;
            }
            if taken < min {
                return Err(self.error(format_args!(
                    "option `{}` lacks its value",
                    options.last().unwrap()
                )));
            }
        }
        let name = tokens[i..].join(" ");
        if name.is_empty() {
            return Err(self.error("names no texture file"));
        }
        if !options.is_empty() {
            warnings.push(format!(
                "{}:{}: material `{}`: texture options {} ignored",
                self.path.display(),
                self.line,
                self.material,
                options.join(" ")
            ));
        }
        let direct = dir.join(&name);
        for candidate in [direct.clone(), dir.join(name.replace('\\', "/"))] {
            if candidate.is_file() {
                return Ok(Some(candidate));
            }
        }
        warnings.push(format!(
            "{}:{}: material `{}`: texture `{name}` not found (looked for `{}`); drawn without it",
            self.path.display(),
            self.line,
            self.material,
            direct.display()
        ));
        Ok(None)
    }
}

/// Parses an MTL text and maps every material; names may repeat.
pub(super) fn parse_library(
    path: &Path,
    text: &str,
    warnings: &mut Vec<String>,
) -> Result<Vec<Material>> {
    let dir = path.parent().unwrap_or(Path::new(""));
    let mut raws: Vec<RawMaterial> = Vec::new();
    let mut ignored: BTreeMap<String, (usize, usize)> = BTreeMap::new();
    for (i, raw_line) in text.lines().enumerate() {
        let n = i + 1;
        let (keyword, rest) = split_keyword(raw_line.trim());
        if keyword.is_empty() || keyword.starts_with('#') {
            continue;
        }
        if keyword == "newmtl" {
            if rest.is_empty() {
                return Err(parse_error(path, Some(n), "`newmtl` names no material"));
            }
            raws.push(RawMaterial {
                name: rest.to_owned(),
                ..Default::default()
            });
            continue;
        }
        let Some(m) = raws.last_mut() else {
            return Err(parse_error(
                path,
                Some(n),
                format!("`{keyword}` before any `newmtl`"),
            ));
        };
        let name = m.name.clone();
        let ctx = Ctx {
            path,
            line: n,
            material: &name,
            keyword,
        };
        match keyword {
            "Kd" => m.kd = Some(ctx.colour(rest, Range::Unit)?),
            "Ks" => m.ks = Some(ctx.colour(rest, Range::Unit)?),
            "Ke" => m.ke = Some(ctx.colour(rest, Range::NonNegative)?),
            "Tf" => m.tf = Some(ctx.colour(rest, Range::Unit)?),
            "Ka" => {
                ctx.colour(rest, Range::Finite)?;
            }
            "Ns" => m.ns = Some(ctx.number(rest, Range::NonNegative)?),
            "Ni" => m.ni = Some(ctx.number(rest, Range::Positive)?),
            "d" => {
                let rest = rest.strip_prefix("-halo").map_or(rest, str::trim);
                m.d = Some(ctx.number(rest, Range::Unit)?);
            }
            "Tr" => m.tr = Some(ctx.number(rest, Range::Unit)?),
            "Pr" => m.pr = Some(ctx.number(rest, Range::Unit)?),
            "Pm" => m.pm = Some(ctx.number(rest, Range::Unit)?),
            "illum" => {
                let value = rest
                    .split_whitespace()
                    .next()
                    .and_then(|w| w.parse::<u32>().ok())
                    .filter(|&v| v <= 10 && rest.split_whitespace().count() == 1)
                    .ok_or_else(|| {
                        ctx.error(format_args!(
                            "`{rest}` is not an illumination model 0 to 10"
                        ))
                    })?;
                m.illum = Some(At { value, line: n });
            }
            "map_Kd" => m.map_kd = ctx.texture(dir, rest, warnings)?,
            "map_Ks" => m.map_ks = ctx.texture(dir, rest, warnings)?,
            "lustre_model" => m.model = Some(ctx.word(rest)?),
            "lustre_alpha" => m.alpha = Some(ctx.number(rest, Range::Positive)?),
            "lustre_alpha_x" => m.alpha_x = Some(ctx.number(rest, Range::Positive)?),
            "lustre_alpha_y" => m.alpha_y = Some(ctx.number(rest, Range::Positive)?),
            "lustre_eta" => m.eta = Some(ctx.colour(rest, Range::Positive)?),
            "lustre_k" => m.k = Some(ctx.colour(rest, Range::NonNegative)?),
            "lustre_blend_weight" => m.blend_weight = Some(ctx.number(rest, Range::Unit)?),
            "lustre_fresnel" => {
                let value = match ctx.word(rest)?.value.to_ascii_lowercase().as_str() {
                    "none" => FresnelKey::None,
                    "conductor" => FresnelKey::Conductor,
                    other => {
                        return Err(
                            ctx.error(format_args!("`{other}` is not `none` or `conductor`"))
                        );
                    }
                };
                m.fresnel = Some(At { value, line: n });
            }
            "lustre_distribution" => {
                let value = match ctx.word(rest)?.value.to_ascii_lowercase().as_str() {
                    "beckmann" => MicrofacetDistribution::Beckmann,
                    "gaussian" => MicrofacetDistribution::Gaussian,
                    "ggx" => MicrofacetDistribution::Ggx,
                    other => {
                        return Err(ctx.error(format_args!(
                            "`{other}` is not `beckmann`, `gaussian` or `ggx`"
                        )));
                    }
                };
                m.distribution = Some(At { value, line: n });
            }
            "lustre_param" => {
                let (param, values) = split_keyword(rest);
                if param.is_empty() {
                    return Err(ctx.error("names no parameter"));
                }
                let values = ctx.numbers(values, Range::Finite)?;
                if values.len() != 1 && values.len() != 3 {
                    return Err(ctx.error(format_args!(
                        "`{param}` takes 1 or 3 numbers; found {}",
                        values.len()
                    )));
                }
                m.params.insert(param.to_owned(), values);
                m.param_line.get_or_insert(n);
            }
            other => {
                ignored.entry(other.to_owned()).or_insert((n, 0)).1 += 1;
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
    let mut materials = raws
        .iter()
        .map(|m| to_material(path, m, warnings))
        .collect::<Result<Vec<_>>>()?;
    decode_diffuse_maps(&mut materials, warnings);
    Ok(materials)
}

/// Decodes each material's `map_Kd` file once ([`Material::diffuse_map`]); a file that cannot be decoded is a warning and the material is drawn without it.
fn decode_diffuse_maps(materials: &mut [Material], warnings: &mut Vec<String>) {
    let mut decoded: HashMap<PathBuf, Option<Arc<Texture>>> = HashMap::new();
    for material in materials {
        let Some(file) = material.diffuse_texture.clone() else {
            continue;
        };
        material.diffuse_map = decoded
            .entry(file)
            .or_insert_with_key(|file| match Texture::load(file) {
                Ok(texture) => Some(Arc::new(texture)),
                Err(e) => {
                    warnings.push(format!(
                        "material `{}`: diffuse texture not used: {e}",
                        material.name
                    ));
                    None
                }
            })
            .clone();
    }
}

/// Maps a material as written to a [`Material`] by the rules of [`crate::obj`].
fn to_material(path: &Path, m: &RawMaterial, warnings: &mut Vec<String>) -> Result<Material> {
    let error = |line: usize, message: String| {
        parse_error(
            path,
            Some(line),
            format!("material `{}`: {message}", m.name),
        )
    };
    let mut warn = |line: usize, message: String| {
        warnings.push(format!(
            "{}:{line}: material `{}`: {message}",
            path.display(),
            m.name
        ));
    };
    // A diffuse map without `Kd` is the colour itself (`Kd` 1), as other viewers draw it.
    let kd = m.kd.map_or(
        if m.map_kd.is_some() {
            Rgb::ONE
        } else {
            Rgb::ZERO
        },
        |a| a.value,
    );
    let ks = m.ks.map_or(Rgb::ZERO, |a| a.value);
    let tf = m.tf.map_or(Rgb::ONE, |a| a.value);
    let opacity = match (m.d, m.tr) {
        (Some(d), _) => d.value,
        (None, Some(tr)) => 1.0 - tr.value,
        (None, None) => 1.0,
    };
    let pbr = m.pr.is_some() || m.pm.is_some();

    if m.model.is_none() {
        let stray = [
            m.alpha.map(|a| (a.line, "lustre_alpha")),
            m.alpha_x.map(|a| (a.line, "lustre_alpha_x")),
            m.alpha_y.map(|a| (a.line, "lustre_alpha_y")),
            m.eta.map(|a| (a.line, "lustre_eta")),
            m.k.map(|a| (a.line, "lustre_k")),
            m.fresnel.map(|a| (a.line, "lustre_fresnel")),
            m.blend_weight.map(|a| (a.line, "lustre_blend_weight")),
            m.distribution
                .filter(|_| !pbr)
                .map(|a| (a.line, "lustre_distribution")),
        ];
        for (line, key) in stray.into_iter().flatten() {
            warn(line, format!("`{key}` without `lustre_model` is ignored"));
        }
    }

    let model = if let Some(At { value: name, line }) = &m.model {
        let line = *line;
        let isotropic_alpha = || -> Result<f32> {
            match (m.alpha, m.alpha_x, m.alpha_y) {
                (Some(a), _, _) => Ok(a.value),
                (None, Some(x), Some(y)) if x.value == y.value => Ok(x.value),
                (None, Some(_), Some(_)) => Err(error(
                    line,
                    format!(
                        "`{name}` is isotropic but `lustre_alpha_x` and `lustre_alpha_y` differ"
                    ),
                )),
                _ => Err(error(line, format!("`{name}` needs `lustre_alpha`"))),
            }
        };
        let rough_conductor = |default: MicrofacetDistribution| -> Result<MaterialModel> {
            let alpha = isotropic_alpha()?;
            let fresnel = match (m.fresnel, m.eta, m.k) {
                (
                    Some(At {
                        value: FresnelKey::None,
                        ..
                    }),
                    _,
                    _,
                ) => ConductorFresnel::None,
                (_, Some(eta), Some(k)) => ConductorFresnel::Complex {
                    eta: eta.value,
                    k: k.value,
                },
                (
                    Some(At {
                        value: FresnelKey::Conductor,
                        line,
                    }),
                    _,
                    _,
                ) => {
                    return Err(error(
                        line,
                        "`lustre_fresnel conductor` needs `lustre_eta` and `lustre_k`".into(),
                    ));
                }
                (None, Some(At { line, .. }), None) | (None, None, Some(At { line, .. })) => {
                    return Err(error(
                        line,
                        "`lustre_eta` and `lustre_k` go together".into(),
                    ));
                }
                (None, None, None) => ConductorFresnel::None,
            };
            Ok(MaterialModel::RoughConductor {
                distribution: m.distribution.map_or(default, |d| d.value),
                alpha,
                fresnel,
                specular: m.ks.map_or(Rgb::ONE, |a| a.value),
            })
        };
        let model = match name.to_ascii_lowercase().as_str() {
            "diffuse" => MaterialModel::Diffuse { reflectance: kd },
            "phong" => MaterialModel::Phong {
                diffuse: kd,
                specular: ks,
                exponent: m
                    .ns
                    .ok_or_else(|| error(line, "`phong` needs `Ns`".into()))?
                    .value,
            },
            "mirror" => MaterialModel::Mirror {
                reflectance: m.ks.map_or(Rgb::ONE, |a| a.value),
            },
            "dielectric" => MaterialModel::Dielectric {
                ior: m
                    .ni
                    .ok_or_else(|| error(line, "`dielectric` needs `Ni`".into()))?
                    .value,
                transmittance: tf,
            },
            "ward" => {
                let alpha = |axis: Option<At<f32>>, key: &str| {
                    axis.or(m.alpha).map(|a| a.value).ok_or_else(|| {
                        error(line, format!("`ward` needs `{key}` or `lustre_alpha`"))
                    })
                };
                MaterialModel::Ward {
                    diffuse: kd,
                    specular: ks,
                    alpha_x: alpha(m.alpha_x, "lustre_alpha_x")?,
                    alpha_y: alpha(m.alpha_y, "lustre_alpha_y")?,
                }
            }
            "beckmann" => {
                if let Some(d) = m
                    .distribution
                    .filter(|d| d.value != MicrofacetDistribution::Beckmann)
                {
                    return Err(error(
                        d.line,
                        "`lustre_distribution` contradicts `lustre_model beckmann`".into(),
                    ));
                }
                rough_conductor(MicrofacetDistribution::Beckmann)?
            }
            "rough-conductor" | "roughconductor" | "conductor" => {
                rough_conductor(MicrofacetDistribution::Beckmann)?
            }
            "blend" => MaterialModel::Blend {
                weight: m
                    .blend_weight
                    .ok_or_else(|| error(line, "`blend` needs `lustre_blend_weight`".into()))?
                    .value,
                first: Box::new(MaterialModel::Diffuse { reflectance: kd }),
                second: Box::new(rough_conductor(MicrofacetDistribution::Beckmann)?),
            },
            _ => MaterialModel::Named {
                model: name.clone(),
                params: m.params.clone(),
            },
        };
        if !matches!(model, MaterialModel::Named { .. }) {
            if let Some(line) = m.param_line {
                warn(
                    line,
                    format!("`lustre_param` is ignored by the built-in model `{name}`"),
                );
            }
        }
        model
    } else if pbr {
        if let Some(line) = m.param_line {
            warn(
                line,
                "`lustre_param` without `lustre_model` is ignored".into(),
            );
        }
        let roughness = m.pr.map_or(1.0, |a| a.value);
        let metallic = m.pm.map_or(0.0, |a| a.value);
        let alpha = roughness * roughness;
        let metal = if alpha > 0.0 {
            MaterialModel::RoughConductor {
                distribution: m
                    .distribution
                    .map_or(MicrofacetDistribution::Ggx, |d| d.value),
                alpha,
                fresnel: ConductorFresnel::None,
                specular: kd,
            }
        } else {
            MaterialModel::Mirror { reflectance: kd }
        };
        if metallic == 0.0 {
            MaterialModel::Diffuse { reflectance: kd }
        } else if metallic == 1.0 {
            metal
        } else {
            MaterialModel::Blend {
                weight: metallic,
                first: Box::new(MaterialModel::Diffuse { reflectance: kd }),
                second: Box::new(metal),
            }
        }
    } else {
        if let Some(line) = m.param_line {
            warn(
                line,
                "`lustre_param` without `lustre_model` is ignored".into(),
            );
        }
        let illum = m.illum.map(|a| a.value);
        let refractive_illum = matches!(illum, Some(4 | 6 | 7));
        let ks_positive = ks.max_element() > 0.0;
        match m.ni {
            Some(ni) if opacity < 1.0 || refractive_illum => MaterialModel::Dielectric {
                ior: ni.value,
                transmittance: tf,
            },
            _ => {
                if let (true, Some(i)) = (refractive_illum, m.illum) {
                    warn(
                        i.line,
                        format!("`illum {}` without `Ni` is not refractive", i.value),
                    );
                }
                if matches!(illum, Some(3 | 5 | 8)) && ks_positive {
                    MaterialModel::Mirror { reflectance: ks }
                } else if ks_positive {
                    match m.ns {
                        Some(ns) if !matches!(illum, Some(0 | 1)) => {
                            if (kd + ks).max_element() > 1.0 {
                                warn(ns.line, "Kd + Ks exceeds 1: the Phong material reflects more than it receives".into());
                            }
                            MaterialModel::Phong {
                                diffuse: kd,
                                specular: ks,
                                exponent: ns.value,
                            }
                        }
                        _ => {
                            let line = m.ks.map_or(0, |a| a.line);
                            warn(
                                line,
                                "`Ks` ignored (no `Ns`, or `illum` 0 or 1): diffuse".into(),
                            );
                            MaterialModel::Diffuse { reflectance: kd }
                        }
                    }
                } else {
                    MaterialModel::Diffuse { reflectance: kd }
                }
            }
        }
    };
    Ok(Material {
        name: m.name.clone(),
        model,
        emission: m.ke.map_or(Rgb::ZERO, |a| a.value),
        diffuse_texture: m.map_kd.clone(),
        diffuse_map: None,
        specular_texture: m.map_ks.clone(),
        opacity,
    })
}
