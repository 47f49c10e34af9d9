//! The Mocu layout language front end (see docs/language.md).
#![deny(unsafe_code)]
