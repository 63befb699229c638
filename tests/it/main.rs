//! One integration-test binary (links once): a module per layer and claim.

mod classic_loop;
mod common;
mod compare_scenes;
mod coupling;
mod curved_reconstruction;
mod every_scale;
mod fig4;
mod friction;
mod gltf_input;
mod haptic_servo;
mod haptics;
mod main_loop;
mod mesh_inputs;
mod pair_events;
mod pipeline;
mod prelude;
mod rapier_semantics;
mod reconstruction_bad_input;
mod reconstruction_properties;
mod rigid_motion;
mod sharp_tools;
mod spinning_drop;
mod stress_scenes;
mod surface;
mod surface_bvh;
mod tool_shapes;
