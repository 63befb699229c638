//! One integration-test binary (links once): a module per layer and claim.

mod common;
mod coupling;
mod fig4;
mod pipeline;
mod reconstruction_bad_input;
mod reconstruction_properties;
mod surface;
