//! Random and low-discrepancy sampling, warps to directions and areas, frames.

mod frame;
mod warp;

pub use frame::Frame;
pub use warp::*;
