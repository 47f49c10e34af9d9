//! World-model values shared by the DataServer, the compiler and every module.
//!
//! Architecture invariant: this crate knows nothing of threads, I/O, the compiler or the
//! renderer. It only defines what a property *is*.

#![forbid(unsafe_code)]

mod guid;
mod kind;
pub mod limits;
mod name;
mod value;

pub use guid::Guid;
pub use kind::ValueKind;
pub use name::PropName;
pub use value::Value;
