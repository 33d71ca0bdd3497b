//! Shared by the GPU tests: open a device or skip, loudly, unless `LUSTRE_REQUIRE_GPU` is set.

use lustre_mpr::{AdapterPreference, GpuContext, MprError};

/// A device for `test`, or `None` (with a printed message) when no adapter
/// exists; panics instead when `LUSTRE_REQUIRE_GPU` is set, and on any other error.
pub fn gpu_or_skip(test: &str) -> Option<GpuContext> {
    match GpuContext::new(AdapterPreference::Hardware) {
        Ok(ctx) => {
            eprintln!(
                "{test}: adapter {} (HDR {:?}, float32 blendable: {})",
                ctx.adapter(),
                ctx.hdr_format(),
                ctx.float32_blendable()
            );
            Some(ctx)
        }
        Err(e @ MprError::NoAdapter { .. }) => {
            if std::env::var_os("LUSTRE_REQUIRE_GPU").is_some() {
                panic!("{test}: LUSTRE_REQUIRE_GPU is set but {e}");
            }
            eprintln!("SKIPPED {test}: {e} (set LUSTRE_REQUIRE_GPU to make this a failure)");
            None
        }
        Err(e) => panic!("{test}: {e}"),
    }
}
