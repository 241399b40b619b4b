//! # rpod — a testbed for spacecraft rendezvous, proximity operations and docking
//!
//! Layers (see the README for the full map):
//! - Bevy-free scientific core, f64, unit-tested alone: [`math`], [`orbit`], [`geometry`],
//!   [`control`], [`actuation`], [`contact`], [`report`].
//! - `sim` feature: the Bevy + rapier layer that turns a scene into a fixed-step `App`.
//! - `viewer` feature: `viewer`, the window (`rpod view`, `rpod replay`).

pub mod actuation;
#[cfg(feature = "sim")]
pub mod bench;
pub mod contact;
pub mod control;
pub mod geometry;
pub mod guarantee;
pub mod math;
pub mod orbit;
pub mod report;
#[cfg(feature = "sim")]
pub mod reproduce;
pub mod scene;
#[cfg(feature = "sim")]
pub mod sim;
#[cfg(feature = "sim")]
pub mod trials;
#[cfg(feature = "viewer")]
pub mod viewer;
