//! Construction from material models: every name, typed errors for bad input.

mod support;

use lustre_brdf::{BrdfError, MODEL_NAMES, from_model};
use lustre_geometry::Rgb;
use lustre_geometry::material::{ConductorFresnel, MaterialModel, MicrofacetDistribution};
use support::named;

#[test]
fn every_named_model_builds_with_defaults_and_reports_its_name() {
    for name in MODEL_NAMES {
        let b = from_model(&named(name, &[])).unwrap_or_else(|e| panic!("{name}: {e}"));
        let expected = if *name == "diffuse" { "lambert" } else { name };
        assert_eq!(b.name(), expected);
    }
}

#[test]
fn unknown_model_and_parameter_are_errors() {
    assert!(
        matches!(from_model(&named("glossy-unicorn", &[])), Err(BrdfError::UnknownModel(m)) if m == "glossy-unicorn")
    );
    assert!(matches!(
        from_model(&named("ward", &[("alpha_x", &[0.1])])),
        Err(BrdfError::UnknownParameter { param, .. }) if param == "alpha_x"
    ));
    assert!(matches!(
        from_model(&named("lambert", &[("reflectance", &[0.1, 0.2])])),
        Err(BrdfError::ParameterArity { got: 2, .. })
    ));
    assert!(matches!(
        from_model(&named("cook-torrance", &[("eta", &[0.2])])),
        Err(BrdfError::MissingParameter { param, .. }) if param == "k"
    ));
}

#[test]
fn out_of_range_parameters_are_errors() {
    let bad = [
        named("lambert", &[("reflectance", &[1.2])]),
        named("cook-torrance", &[("roughness", &[-0.1])]),
        named("ward", &[("alpha-x", &[0.0])]),
        named(
            "modified-phong",
            &[("diffuse", &[0.7]), ("specular", &[0.5])],
        ),
        named("oren-nayar", &[("sigma", &[f32::NAN])]),
        named("schlick", &[("isotropy", &[1.5])]),
        named("strauss", &[("smoothness", &[1.0])]),
        named("poulin-fournier", &[("height", &[2.0])]),
        named("htsg", &[("tau", &[0.0])]),
        named("dielectric", &[("ior", &[-1.0])]),
        named("cook-torrance", &[("smith", &[0.5])]),
        named("mirror", &[("ior", &[1.5]), ("f0", &[0.5])]),
        named("lafortune", &[("lobe", &[1.0, 1.0, 1.0, -2.0, 0.5])]),
        MaterialModel::Diffuse {
            reflectance: Rgb::new(0.5, -0.1, 0.5),
        },
        MaterialModel::RoughConductor {
            distribution: MicrofacetDistribution::Beckmann,
            alpha: -0.2,
            fresnel: ConductorFresnel::None,
            specular: Rgb::ONE,
        },
        MaterialModel::Phong {
            diffuse: Rgb::splat(0.8),
            specular: Rgb::splat(0.5),
            exponent: 10.0,
        },
        MaterialModel::Blend {
            weight: 1.5,
            first: Box::new(MaterialModel::Diffuse {
                reflectance: Rgb::ONE,
            }),
            second: Box::new(MaterialModel::Mirror {
                reflectance: Rgb::ONE,
            }),
        },
    ];
    for m in bad {
        let r = from_model(&m);
        assert!(
            matches!(r, Err(BrdfError::OutOfRange { .. })),
            "{m:?} gave {:?}",
            r.map(|b| b.name())
        );
    }
}

#[test]
fn errors_name_the_model_and_parameter() {
    let e = from_model(&named("ward", &[("alpha-y", &[-1.0])])).unwrap_err();
    let msg = e.to_string();
    assert!(msg.contains("ward") && msg.contains("alpha-y"), "{msg}");
}
