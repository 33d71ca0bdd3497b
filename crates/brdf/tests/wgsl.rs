//! The WGSL BRDF module: naga parses and validates it on any machine, and on a GPU (or lavapipe) a compute shader built on it matches the Rust models.
//!
//! The GPU test prints a message and passes when no adapter exists, unless
//! `LUSTRE_REQUIRE_GPU` is set, in which case a missing adapter fails it.

mod support;

use std::borrow::Cow;

use glam::Vec3;
use lustre_brdf::diefenbach_fit::{DIEFENBACH_AMPLITUDE, DIEFENBACH_EXPONENT_SCALE};
use lustre_brdf::microfacet::{Distribution, Shadowing};
use lustre_brdf::models::{
    CookTorrance, DiefenbachPhong, Lambert, ModifiedPhong, Ward, WardNormalisation,
};
use lustre_brdf::shaders::BRDF_WGSL;
use lustre_brdf::{Brdf, Fresnel};
use lustre_geometry::Rgb;
use lustre_geometry::material::MicrofacetDistribution;
use lustre_mpr::{AdapterPreference, GpuContext, MprError};
use support::Rng;
use wgpu::util::DeviceExt;

/// Parses and validates `src` with naga, panicking with the diagnostic.
fn validate(src: &str) -> naga::Module {
    let module = naga::front::wgsl::parse_str(src)
        .unwrap_or_else(|e| panic!("WGSL parse error:\n{}", e.emit_to_string(src)));
    naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::empty(),
    )
    .validate(&module)
    .unwrap_or_else(|e| panic!("WGSL validation error:\n{}", e.emit_to_string(src)));
    module
}

#[test]
fn brdf_module_parses_and_validates_with_naga() {
    let module = validate(BRDF_WGSL);
    for name in [
        "brdf_lambert",
        "brdf_modified_phong",
        "brdf_diefenbach_phong",
        "brdf_ward_isotropic",
        "brdf_cook_torrance_beckmann",
    ] {
        assert!(
            module
                .functions
                .iter()
                .any(|(_, f)| f.name.as_deref() == Some(name)),
            "{name} missing"
        );
    }
    validate(&compute_source());
}

/// Number of vec4 inputs per case and of models (outputs) per case.
const INPUTS: usize = 7;
/// Models evaluated per case, in output order.
const MODELS: [&str; 5] = [
    "lambert",
    "modified-phong",
    "diefenbach-phong",
    "ward",
    "cook-torrance",
];

/// The compute shader: the BRDF module plus one entry point evaluating every model per case.
fn compute_source() -> String {
    format!(
        "{BRDF_WGSL}
@group(0) @binding(0) var<storage, read> cases: array<vec4f>;
@group(0) @binding(1) var<storage, read_write> results: array<vec4f>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3u) {{
    let i = id.x;
    if i >= arrayLength(&cases) / {INPUTS}u {{
        return;
    }}
    let wi = cases[i * {INPUTS}u].xyz;
    let wo = cases[i * {INPUTS}u + 1u].xyz;
    let kd = cases[i * {INPUTS}u + 2u].xyz;
    let ks = cases[i * {INPUTS}u + 3u].xyz;
    let p = cases[i * {INPUTS}u + 4u];
    let eta = cases[i * {INPUTS}u + 5u].xyz;
    let k = cases[i * {INPUTS}u + 6u].xyz;
    let o = i * 5u;
    results[o] = vec4f(brdf_lambert(wi, wo, kd), 0.0);
    results[o + 1u] = vec4f(brdf_modified_phong(wi, wo, kd, ks, p.y), 0.0);
    results[o + 2u] = vec4f(brdf_diefenbach_phong(wi, wo, kd, ks, p.x, p.z, p.w), 0.0);
    results[o + 3u] = vec4f(brdf_ward_isotropic(wi, wo, kd, ks, p.x), 0.0);
    results[o + 4u] = vec4f(brdf_cook_torrance_beckmann(wi, wo, kd, ks, p.x, eta, k), 0.0);
}}
"
    )
}

/// One random case: directions and parameters.
struct Case {
    wi: Vec3,
    wo: Vec3,
    kd: Rgb,
    ks: Rgb,
    alpha: f32,
    exponent: f32,
    eta: Rgb,
    k: Rgb,
}

impl Case {
    /// The Rust models in [`MODELS`] order.
    fn rust(&self) -> [Rgb; 5] {
        let dist = Distribution::new(MicrofacetDistribution::Beckmann, self.alpha, "gpu").unwrap();
        [
            Lambert::new(self.kd).unwrap().eval(self.wi, self.wo),
            ModifiedPhong::new(self.kd, self.ks, self.exponent)
                .unwrap()
                .eval(self.wi, self.wo),
            DiefenbachPhong::new(self.kd, self.ks, self.alpha)
                .unwrap()
                .eval(self.wi, self.wo),
            Ward::new(
                self.kd,
                self.ks,
                self.alpha,
                self.alpha,
                WardNormalisation::Original,
            )
            .unwrap()
            .eval(self.wi, self.wo),
            CookTorrance::new(
                self.kd,
                self.ks,
                dist,
                Shadowing::Smith,
                Fresnel::Conductor {
                    eta: self.eta,
                    k: self.k,
                },
            )
            .unwrap()
            .eval(self.wi, self.wo),
        ]
    }
}

/// Random cases: directions uniform over the hemisphere within 87° of the normal (and a few below it), kd + ks ≤ 1, α in [0.05, 0.5], exponents in [1, 100], conductor indices around gold's and copper's.
fn cases(n: usize) -> Vec<Case> {
    let mut rng = Rng::new(0x6770_7521);
    (0..n)
        .map(|j| {
            let mut wi = rng.upper(0.05);
            if j % 50 == 0 {
                wi.z = -wi.z;
            }
            let kd = Rgb::new(rng.f32(), rng.f32(), rng.f32()) * 0.5;
            let ks = Rgb::new(rng.f32(), rng.f32(), rng.f32()) * 0.5;
            Case {
                wi,
                wo: rng.upper(0.05),
                kd,
                ks,
                alpha: 0.05 + 0.45 * rng.f32(),
                exponent: 1.0 + 99.0 * rng.f32(),
                eta: Rgb::new(0.1 + rng.f32(), 0.2 + rng.f32(), 0.3 + rng.f32()),
                k: Rgb::new(2.0 + 2.0 * rng.f32(), 1.5 + rng.f32(), 1.0 + rng.f32()),
            }
        })
        .collect()
}

/// Runs the compute shader on `cases`; `None` when no adapter exists. The device is opened as the renderer opens it ([`GpuContext`]: without a desktop session, libwayland's `XDG_RUNTIME_DIR` message is kept off stderr).
fn run_on_gpu(cases: &[Case]) -> Option<(String, Vec<f32>)> {
    let ctx = match GpuContext::new(AdapterPreference::Hardware) {
        Ok(ctx) => ctx,
        Err(MprError::NoAdapter { .. }) => return None,
        Err(e) => panic!("opening the GPU failed: {e}"),
    };
    let (device, queue) = (&ctx.device, &ctx.queue);
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("brdf-test"),
        source: wgpu::ShaderSource::Wgsl(Cow::Owned(compute_source())),
    });
    let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some("brdf-test"),
        layout: None,
        module: &module,
        entry_point: Some("main"),
        compilation_options: Default::default(),
        cache: None,
    });
    let mut input = Vec::with_capacity(cases.len() * INPUTS * 4);
    for c in cases {
        for v in [
            c.wi.extend(0.0).to_array(),
            c.wo.extend(0.0).to_array(),
            c.kd.extend(0.0).to_array(),
            c.ks.extend(0.0).to_array(),
            [
                c.alpha,
                c.exponent,
                DIEFENBACH_AMPLITUDE,
                DIEFENBACH_EXPONENT_SCALE,
            ],
            c.eta.extend(0.0).to_array(),
            c.k.extend(0.0).to_array(),
        ] {
            input.extend_from_slice(&v);
        }
    }
    let bytes: Vec<u8> = input.iter().flat_map(|f| f.to_le_bytes()).collect();
    let cases_buf = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("cases"),
        contents: &bytes,
        usage: wgpu::BufferUsages::STORAGE,
    });
    let out_size = (cases.len() * MODELS.len() * 16) as u64;
    let results = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("results"),
        size: out_size,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let staging = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("staging"),
        size: out_size,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("brdf-test"),
        layout: &pipeline.get_bind_group_layout(0),
        entries: &[
            wgpu::BindGroupEntry {
                binding: 0,
                resource: cases_buf.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 1,
                resource: results.as_entire_binding(),
            },
        ],
    });
    let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
    {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor::default());
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &bind_group, &[]);
        pass.dispatch_workgroups(cases.len().div_ceil(64) as u32, 1, 1);
    }
    encoder.copy_buffer_to_buffer(&results, 0, &staging, 0, out_size);
    queue.submit([encoder.finish()]);
    let slice = staging.slice(..);
    slice.map_async(wgpu::MapMode::Read, |r| {
        r.expect("mapping the results failed")
    });
    device
        .poll(wgpu::PollType::wait_indefinitely())
        .expect("device poll failed");
    let data = slice.get_mapped_range().expect("results not mapped");
    let out = data
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect();
    Some((ctx.adapter().to_string(), out))
}

#[test]
fn gpu_brdfs_match_the_rust_models() {
    let cases = cases(4096);
    let Some((adapter, out)) = run_on_gpu(&cases) else {
        if std::env::var_os("LUSTRE_REQUIRE_GPU").is_some() {
            panic!("LUSTRE_REQUIRE_GPU is set but no Vulkan adapter was found");
        }
        eprintln!(
            "SKIPPED gpu_brdfs_match_the_rust_models: no GPU adapter (install mesa-vulkan-drivers for lavapipe; set LUSTRE_REQUIRE_GPU to make this a failure)"
        );
        return;
    };
    eprintln!("GPU BRDF test on {adapter}");
    // f32 on both sides with different operation orders (and the GPU's
    // exp/pow precision): 1e-4 relative, with an absolute floor of 1e-6 /sr
    // for values that underflow towards zero.
    let mut worst = (0.0f32, "", 0usize);
    for (j, c) in cases.iter().enumerate() {
        for (m, want) in c.rust().iter().enumerate() {
            let o = (j * MODELS.len() + m) * 4;
            let got = Rgb::new(out[o], out[o + 1], out[o + 2]);
            for ch in 0..3 {
                let err = (got[ch] - want[ch]).abs() / want[ch].abs().max(1e-2);
                if err > worst.0 {
                    worst = (err, MODELS[m], j);
                }
                assert!(
                    (got[ch] - want[ch]).abs() <= 1e-4 * want[ch].abs() + 1e-6,
                    "{} case {j} channel {ch}: GPU {} vs Rust {} (wi = {}, wo = {}, α = {}, n = {})",
                    MODELS[m],
                    got[ch],
                    want[ch],
                    c.wi,
                    c.wo,
                    c.alpha,
                    c.exponent
                );
            }
        }
    }
    eprintln!(
        "largest relative difference {:.2e} ({} case {})",
        worst.0, worst.1, worst.2
    );
}
