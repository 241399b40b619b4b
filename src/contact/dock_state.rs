//! The docking states of both mechanisms (cone/slot and soft capture), Bevy-free: one list
//! gives the enum, its `dock.state` codes, its names and [`DockState::ALL`], so the simulation
//! (`sim::docking`, which re-exports it), the trials, the Sequencer and the plots agree.

use serde::Serialize;

/// Defines [`DockState`], its codes and its names from one list, so that a new state cannot
/// lack a code, a name, a plot label or a place in [`DockState::ALL`].
macro_rules! dock_states {
    ($($(#[$doc:meta])* $variant:ident = $code:literal, $name:literal;)*) => {
        /// Docking state.
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
        #[serde(rename_all = "SCREAMING_SNAKE_CASE")]
        pub enum DockState {
            $($(#[$doc])* $variant,)*
        }

        impl DockState {
            /// Every state, in the order of its code (the trajectory column `dock.state`).
            pub const ALL: &'static [DockState] = &[$(DockState::$variant),*];
            /// Every state's name, in the order of [`DockState::ALL`].
            pub const NAMES: &'static [&'static str] = &[$($name),*];
            /// A number for the trajectory column `dock.state`.
            pub fn code(self) -> f64 {
                match self {
                    $(DockState::$variant => $code as f64,)*
                }
            }
            /// The name used in events and summaries.
            pub fn name(self) -> &'static str {
                match self {
                    $(DockState::$variant => $name,)*
                }
            }
        }
    };
}

dock_states! {
    /// No magnet and no contact (yet, or again after a contact that ended without the chaser
    /// moving away).
    Free = 0, "FREE";
    /// Magnet on, no contact yet.
    Attracting = 1, "ATTRACTING";
    /// Cone touching the slot, not seated.
    Contact = 2, "CONTACT";
    /// Seated within the latch tolerances, waiting out the dwell.
    SoftCapture = 3, "SOFT_CAPTURE";
    /// Latched: a fixed joint holds the bodies.
    Latched = 4, "LATCHED";
    /// The cone bounced out of the slot.
    Rebound = 5, "REBOUND";
    /// Stuck in the slot without seating.
    Jammed = 6, "JAMMED";
    /// Failed: passed beside the slot, or another part collided.
    Missed = 7, "MISSED";
    /// Released from the latch by a command (undocking); final.
    Released = 8, "RELEASED";
    /// Soft capture: the capture latches hold the chaser's ring to the target's ring; the
    /// chaser hangs on the platform's legs (attenuation, then retraction).
    SoftCaptured = 9, "SOFT_CAPTURED";
    /// Soft capture, the platform retracted to its retracted stroke; the hooks wait for the
    /// interface to align.
    Retracted = 10, "RETRACTED";
    /// The structural hooks are closed (a stiff compliant joint).
    HardDocked = 11, "HARD_DOCKED";
}

impl DockState {
    /// The state of a trajectory's `dock.state` code, if it is one.
    pub fn from_code(code: f64) -> Option<DockState> {
        DockState::ALL.iter().copied().find(|s| s.code() == code)
    }
    /// The state of an event's or summary's name, if it is one.
    pub fn from_name(name: &str) -> Option<DockState> {
        DockState::ALL.iter().copied().find(|s| s.name() == name)
    }
    /// The state a successful docking ends in with this mechanism: LATCHED for the cone and
    /// slot, HARD_DOCKED for the soft-capture mechanism (its hooks closed).
    pub fn docked_end_state(mechanism: &crate::scene::Mechanism) -> DockState {
        match mechanism {
            crate::scene::Mechanism::ConeSlot => DockState::Latched,
            crate::scene::Mechanism::SoftCapture(_) => DockState::HardDocked,
        }
    }
    /// Docked: latched, or held by a soft-capture mechanism (captured, retracted, hard docked).
    pub fn docked(self) -> bool {
        matches!(
            self,
            DockState::Latched
                | DockState::SoftCaptured
                | DockState::Retracted
                | DockState::HardDocked
        )
    }
}
