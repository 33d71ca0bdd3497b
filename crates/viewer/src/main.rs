//! `lustre`: information about a scene, Mitsuba 3 export, headless
//! rendering (`lustre render`, see [`render`]), and photon files traced,
//! merged and read in bounded memory (`lustre trace`, `lustre merge`, see
//! [`trace`]).

mod gpu_frame;
mod ibr_cache;
mod render;
mod render_density;
mod render_frames;
mod render_stream;
mod scene_arg;
mod trace;
mod view;

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Context;
use clap::{Parser, Subcommand};
use lustre_geometry::SurfaceKind;
use lustre_geometry::light::Light;
use lustre_geometry::mitsuba::{self, ExportOptions};

/// Lustre: interactive global illumination of glossy, mirror and refractive scenes.
#[derive(Debug, Parser)]
#[command(name = "lustre", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Print a scene's triangles, surfaces, materials, lights and bounds, or a photon file's header.
    Info {
        /// A built-in scene (cornell, glosbox, tree, mirrors, bathroom, cardioid, pool, stained-glass, pyramid, house), an OBJ or glTF 2.0 file (`.gltf`, `.glb`), or a photon file (`.lph`).
        scene: String,
    },
    /// Write a scene as Mitsuba 3 XML, with its meshes as PLY files beside it.
    ExportMitsuba {
        /// A built-in scene (cornell, glosbox, tree, mirrors, bathroom, cardioid, pool, stained-glass, pyramid, house), or an OBJ or glTF 2.0 file (`.gltf`, `.glb`).
        scene: String,
        /// The XML file to write.
        out: PathBuf,
        /// Image width and height in pixels, `WxH`.
        #[arg(long, default_value = "256x256", value_parser = parse_size)]
        size: (u32, u32),
        /// Samples per pixel of the reference render.
        #[arg(long, default_value_t = 1024)]
        spp: u32,
        /// Export materials Mitsuba lacks (Phong, Ward, ...) as their diffuse
        /// part, with a warning, instead of failing.
        #[arg(long)]
        approximate: bool,
        /// Export each isotropic point light as a sphere of this radius in
        /// metres emitting the same power (radiance I / (π R²)), so the path
        /// tracer finds caustics of point lights through mirrors and water.
        #[arg(long, value_name = "R", allow_negative_numbers = true)]
        point_light_radius: Option<f32>,
    },
    /// Write a scene as glTF 2.0: binary (`.glb`) or JSON with an embedded buffer (`.gltf`)
    ExportGltf {
        /// A built-in scene (cornell, glosbox, tree, mirrors, bathroom, cardioid, pool, stained-glass, pyramid, house), or an OBJ or glTF 2.0 file (`.gltf`, `.glb`).
        scene: String,
        /// The file to write, `.glb` or `.gltf`.
        out: PathBuf,
    },
    /// Render a scene to an EXR or PNG file (photon splatting, Stürzlinger & Bastos 1997).
    Render(render::RenderArgs),
    /// Open a scene in an interactive window: the same frame as `render`, lit progressively in the background, with orbit and fly cameras, a panel, camera paths and screenshots.
    View(view::ViewArgs),
    /// Trace photons into a photon file on disk in bounded memory (`lustre render --photons-file` reads it).
    Trace(trace::TraceArgs),
    /// Merge the photon files of one run's batches (`lustre trace --batch I/N`) into the file of the whole run.
    Merge {
        /// The batch files, in any order.
        #[arg(required = true)]
        inputs: Vec<PathBuf>,
        /// The merged file to write.
        #[arg(long)]
        out: PathBuf,
    },
}

/// Exit status when no GPU adapter (not even the software one) exists, so scripts can skip rather than fail.
const EXIT_NO_ADAPTER: u8 = 77;

/// Parses `WxH` into a width and height, both at least 1.
fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("`{s}` is not WIDTHxHEIGHT, e.g. 640x480"))?;
    let parse = |v: &str| match v.trim().parse::<u32>() {
        Ok(n) if n > 0 && n <= 16384 => Ok(n),
        _ => Err(format!("`{v}` is not a size between 1 and 16384")),
    };
    Ok((parse(w)?, parse(h)?))
}

fn info(arg: &str) -> anyhow::Result<()> {
    let loaded = scene_arg::load(arg)?;
    let scene = &loaded.scene;
    let bounds = scene.bounds();
    println!("scene       {}", scene.name);
    println!("triangles   {}", scene.triangle_count());
    println!(
        "meshes      {} in {} objects",
        scene.meshes().len(),
        scene.objects().len()
    );
    let planar = scene
        .surfaces()
        .iter()
        .filter(|s| matches!(s.kind, SurfaceKind::Planar(_)))
        .count();
    let area: f32 = scene.surfaces().iter().map(|s| s.area).sum();
    println!(
        "surfaces    {} ({planar} planar, {} curved), {area:.4} m² in all",
        scene.surfaces().len(),
        scene.surfaces().len() - planar
    );
    println!("materials   {}", scene.materials().len());
    for m in scene.materials() {
        let emits = if m.is_emissive() {
            format!(", emits {:.4?} W/(m² sr)", m.emission.to_array())
        } else {
            String::new()
        };
        println!("  {:<14} {}{emits}", m.name, m.model.name());
        match (&m.diffuse_map, &m.diffuse_texture) {
            (Some(map), _) => println!(
                "  {:<14} diffuse map {} ({} × {} texels)",
                "",
                map.name(),
                map.width(),
                map.height()
            ),
            (None, Some(file)) => {
                println!("  {:<14} diffuse map {} (not decoded)", "", file.display())
            }
            (None, None) => {}
        }
    }
    println!("lights      {}", scene.lights().len());
    for light in scene.lights() {
        let kind = match light {
            Light::Point(_) => "point",
            Light::OrientedPoint(_) => "oriented point",
            Light::Spot(_) => "spot",
            Light::Area(_) => "area",
        };
        println!("  {kind:<14} power {:.4?} W", light.power().to_array());
    }
    println!("power       {:.4?} W", scene.total_power().to_array());
    println!("mobile      {}", scene.mobile_objects().len());
    for mobile in scene.mobile_objects() {
        let object = &scene.objects()[mobile.object as usize];
        let triangles: usize = object
            .meshes
            .iter()
            .map(|&m| scene.meshes()[m as usize].indices.len())
            .sum();
        println!(
            "  {:<14} {triangles} triangles, {} keyframes over {} s ({:?})",
            object.name,
            mobile.path.keyframes().len(),
            mobile.path.duration(),
            mobile.path.end()
        );
    }
    println!(
        "bounds      {:.4?} .. {:.4?}",
        bounds.min.to_array(),
        bounds.max.to_array()
    );
    let camera = scene.camera();
    println!(
        "camera      position {:.4?} target {:.4?} up {:.4?} fov_y {:.4}°",
        camera.position.to_array(),
        camera.target.to_array(),
        camera.up.to_array(),
        camera.fov_y_degrees
    );
    if loaded.degenerate_triangles_dropped > 0 {
        println!(
            "dropped     {} degenerate triangles",
            loaded.degenerate_triangles_dropped
        );
    }
    for w in &loaded.warnings {
        println!("warning     {w}");
    }
    Ok(())
}

/// `lustre export-gltf`: the scene as glTF 2.0, each approximation a warning on stderr.
fn export_gltf(arg: &str, out: &std::path::Path) -> anyhow::Result<()> {
    anyhow::ensure!(
        lustre_geometry::is_gltf(out),
        "{}: the glTF file must end in .glb or .gltf",
        out.display()
    );
    let loaded = scene_arg::load(arg)?;
    let warnings = lustre_geometry::gltf::export_gltf(&loaded.scene, out)
        .with_context(|| format!("cannot export `{arg}` to {}", out.display()))?;
    for w in &warnings {
        eprintln!("warning: {w}");
    }
    println!("wrote {}", out.display());
    Ok(())
}

fn export(
    arg: &str,
    out: &std::path::Path,
    size: (u32, u32),
    spp: u32,
    approximate: bool,
    point_light_radius: Option<f32>,
) -> anyhow::Result<()> {
    if let Some(r) = point_light_radius {
        anyhow::ensure!(
            r.is_finite() && r > 0.0,
            "--point-light-radius must be a positive, finite radius in metres, not {r}"
        );
    }
    let loaded = scene_arg::load(arg)?;
    let options = ExportOptions {
        width: size.0,
        height: size.1,
        spp,
        approximate,
        point_light_radius,
        ..ExportOptions::default()
    };
    let report = mitsuba::export(&loaded.scene, out, &options)
        .with_context(|| format!("cannot export `{arg}` to {}", out.display()))?;
    for w in &report.warnings {
        eprintln!("warning: {w}");
    }
    println!("wrote {}", out.display());
    Ok(())
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match &cli.command {
        Command::Info { scene } if scene.to_ascii_lowercase().ends_with(".lph") => {
            trace::info(std::path::Path::new(scene))
        }
        Command::Info { scene } => info(scene),
        Command::ExportMitsuba {
            scene,
            out,
            size,
            spp,
            approximate,
            point_light_radius,
        } => export(scene, out, *size, *spp, *approximate, *point_light_radius),
        Command::ExportGltf { scene, out } => export_gltf(scene, out),
        Command::Render(args) => render::run(args),
        Command::View(args) => view::run(args.clone()),
        Command::Trace(args) => trace::run(args),
        Command::Merge { inputs, out } => trace::merge(inputs, out),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("lustre: {e:#}");
            let no_adapter = e.chain().any(|c| {
                matches!(
                    c.downcast_ref::<lustre_mpr::MprError>(),
                    Some(lustre_mpr::MprError::NoAdapter { .. })
                )
            });
            if no_adapter {
                ExitCode::from(EXIT_NO_ADAPTER)
            } else {
                ExitCode::FAILURE
            }
        }
    }
}
