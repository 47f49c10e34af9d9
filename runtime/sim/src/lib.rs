//! The built-in simulator: USVs, UGVs and UAVs under `root.vehicles`, appearing over time,
//! following the operator's goals (`nav.goal_throttle`, `nav.goal_rudder`) or their own
//! guidance (`goto`, `return_home`, an assigned route), with fuel, engine, link quality,
//! refusals with reasons, routes as waypoint chains, and a synthetic camera stream per
//! vehicle through a listener object.
//!
//! Deterministic under a seed: [`Sim::step`] advances simulated time by an explicit `dt`,
//! and the module ticks it at a fixed `dt`, so two runs with one seed give one world.
//!
//! Architecture invariant: the simulator knows nothing of layouts or displays; it talks
//! only through the DataServer, exactly as a protocol module would.

#![forbid(unsafe_code)]

mod camera;
mod rng;
mod sim;
mod vehicle;

pub use sim::{Sim, SimConfig, SimModule, register};
pub use vehicle::VehicleKind;
