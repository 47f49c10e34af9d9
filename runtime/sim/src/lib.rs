//! The built-in simulator: USVs, UGVs and UAVs under `root.vehicles`, appearing over time,
//! following the operator's goals (`nav.goal_throttle`, `nav.goal_rudder`) or their own
//! guidance (`goto`, `return_home`, an assigned route), with fuel, engine, link quality,
//! refusals with reasons, routes as waypoint chains, a drive and a payload camera per vehicle
//! (synthetic pictures that move with it, `camera.rs`) through listener objects, and a
//! manipulator on each UGV (`manipulator.rs`).
//!
//! Deterministic under a seed: [`Sim::step`] advances simulated time by an explicit `dt`,
//! and the module ticks it at a fixed `dt`, so two runs with one seed give one world.
//!
//! Architecture invariant: the simulator knows nothing of layouts or displays; it talks
//! only through the DataServer, exactly as a protocol module would.

#![forbid(unsafe_code)]

pub mod camera;
mod manipulator;
mod rng;
mod sim;
mod vehicle;

pub use sim::{MAX_CAMERA, Sim, SimConfig, SimModule, register};
pub use vehicle::VehicleKind;
