//! acr: adaptive cluster rendering of pbrt-v3 scenes. This crate holds the renderer core and the
//! command line; the parser and the plugins live in their own crates.

pub mod cli;

pub use acr_parser as parser;
