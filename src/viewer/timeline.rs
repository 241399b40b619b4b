//! The replay timeline: current time, play/pause, speed (0.1× to 1000× real time), seeking and
//! event markers. Plain Rust, no window: the viewer drives it with the wall-clock frame time and
//! reads `t_s` back; the unit tests below drive it by hand.

/// Slowest playback, × real time.
pub const MIN_SPEED: f64 = 0.1;
/// Fastest playback, × real time.
pub const MAX_SPEED: f64 = 1000.0;
/// The speeds the `faster`/`slower` controls step through, × real time.
pub const SPEED_LADDER: [f64; 13] = [
    0.1, 0.2, 0.5, 1.0, 2.0, 5.0, 10.0, 20.0, 50.0, 100.0, 200.0, 500.0, 1000.0,
];

/// What an event marker on the scrubber stands for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MarkerKind {
    /// `contact_start` between any parts.
    Contact,
    /// `collision`: a contact that is not between two docking parts.
    Collision,
    /// `guarantee_violated`.
    Violation,
    /// `docking_state` to `LATCHED`.
    Latch,
    /// Any other event (`guarantee_restored`, other docking states, …).
    Other,
}

/// One event on the timeline.
#[derive(Debug, Clone, PartialEq)]
pub struct Marker {
    /// Simulated time of the event, s.
    pub t_s: f64,
    /// Kind.
    pub kind: MarkerKind,
    /// Short text (event kind and what it names).
    pub label: String,
}

impl Marker {
    /// Classifies one `events.jsonl` object (`t_s`, `kind`, details).
    pub fn from_event(ev: &serde_json::Value) -> Option<Self> {
        let t_s = ev.get("t_s")?.as_f64()?;
        let kind_s = ev.get("kind")?.as_str()?;
        let s = |k: &str| ev.get(k).and_then(|v| v.as_str()).unwrap_or("");
        let (kind, label) = match kind_s {
            "contact_start" => (
                MarkerKind::Contact,
                format!("contact {} - {}", s("a"), s("b")),
            ),
            "collision" => (
                MarkerKind::Collision,
                format!("collision {} - {}", s("a"), s("b")),
            ),
            "guarantee_violated" => (MarkerKind::Violation, format!("violated {}", s("name"))),
            "docking_state" if s("to") == "LATCHED" => (MarkerKind::Latch, "LATCHED".to_string()),
            "docking_state" => (MarkerKind::Other, format!("docking {}", s("to"))),
            other => (MarkerKind::Other, other.to_string()),
        };
        Some(Self { t_s, kind, label })
    }
}

/// Playback state of a recorded run.
#[derive(Debug, Clone)]
pub struct Timeline {
    /// Current simulated time shown, s.
    pub t_s: f64,
    /// First recorded time, s.
    pub start_s: f64,
    /// Last recorded time, s.
    pub end_s: f64,
    /// Interval between recorded rows, s (one `step`).
    pub row_dt_s: f64,
    /// Playback speed, simulated seconds per wall-clock second.
    speed: f64,
    /// Playing (true) or paused.
    pub playing: bool,
    /// Event markers, sorted by time.
    pub markers: Vec<Marker>,
}

impl Timeline {
    /// A paused timeline at `start_s`, speed 1×. Markers are sorted by time.
    pub fn new(start_s: f64, end_s: f64, row_dt_s: f64, mut markers: Vec<Marker>) -> Self {
        markers.sort_by(|a, b| a.t_s.total_cmp(&b.t_s));
        Self {
            t_s: start_s,
            start_s,
            end_s: end_s.max(start_s),
            row_dt_s: if row_dt_s > 0.0 { row_dt_s } else { 0.1 },
            speed: 1.0,
            playing: false,
            markers,
        }
    }

    /// Playback speed, × real time.
    pub fn speed(&self) -> f64 {
        self.speed
    }

    /// Sets the speed, clamped to [`MIN_SPEED`, `MAX_SPEED`]; returns the speed set.
    pub fn set_speed(&mut self, speed: f64) -> f64 {
        self.speed = if speed.is_finite() {
            speed.clamp(MIN_SPEED, MAX_SPEED)
        } else {
            1.0
        };
        self.speed
    }

    /// Next speed up the ladder (stays at the top).
    pub fn faster(&mut self) -> f64 {
        let s = SPEED_LADDER
            .iter()
            .copied()
            .find(|&v| v > self.speed * (1.0 + 1e-9))
            .unwrap_or(MAX_SPEED);
        self.set_speed(s)
    }

    /// Next speed down the ladder (stays at the bottom).
    pub fn slower(&mut self) -> f64 {
        let s = SPEED_LADDER
            .iter()
            .rev()
            .copied()
            .find(|&v| v < self.speed * (1.0 - 1e-9))
            .unwrap_or(MIN_SPEED);
        self.set_speed(s)
    }

    /// Jumps to `t_s`, clamped to the recording.
    pub fn seek(&mut self, t_s: f64) {
        if t_s.is_finite() {
            self.t_s = t_s.clamp(self.start_s, self.end_s);
        }
    }

    /// Position as a fraction of the recording, 0 to 1 (for the scrubber).
    pub fn fraction(&self) -> f64 {
        let span = self.end_s - self.start_s;
        if span > 0.0 {
            (self.t_s - self.start_s) / span
        } else {
            0.0
        }
    }

    /// Seeks to a fraction of the recording (scrubber click), clamped to 0..1.
    pub fn seek_fraction(&mut self, f: f64) {
        let f = if f.is_finite() {
            f.clamp(0.0, 1.0)
        } else {
            0.0
        };
        self.seek(self.start_s + f * (self.end_s - self.start_s));
    }

    /// Play/pause. Playing from the end restarts at the beginning.
    pub fn toggle_play(&mut self) {
        if !self.playing && self.t_s >= self.end_s {
            self.t_s = self.start_s;
        }
        self.playing = !self.playing;
    }

    /// Advances by `wall_dt_s` of wall-clock time at the current speed when playing; stops at
    /// the end. Returns the new time.
    pub fn advance(&mut self, wall_dt_s: f64) -> f64 {
        if self.playing && wall_dt_s > 0.0 {
            self.t_s += wall_dt_s * self.speed;
            if self.t_s >= self.end_s {
                self.t_s = self.end_s;
                self.playing = false;
            }
        }
        self.t_s
    }

    /// Pauses and moves one recorded row forward (`+1`) or back (`-1`).
    pub fn step(&mut self, dir: i32) {
        self.playing = false;
        self.seek(self.t_s + f64::from(dir.signum()) * self.row_dt_s);
    }

    /// Seeks to the first marker strictly after the current time, if any; returns it.
    pub fn next_marker(&mut self) -> Option<&Marker> {
        let t = self.t_s;
        let i = self.markers.iter().position(|m| m.t_s > t + 1e-9)?;
        self.t_s = self.markers[i].t_s.clamp(self.start_s, self.end_s);
        Some(&self.markers[i])
    }

    /// Seeks to the last marker strictly before the current time, if any; returns it.
    pub fn prev_marker(&mut self) -> Option<&Marker> {
        let t = self.t_s;
        let i = self.markers.iter().rposition(|m| m.t_s < t - 1e-9)?;
        self.t_s = self.markers[i].t_s.clamp(self.start_s, self.end_s);
        Some(&self.markers[i])
    }

    /// Markers at or before the current time (what has happened so far).
    pub fn past_markers(&self) -> impl Iterator<Item = &Marker> {
        let t = self.t_s;
        self.markers.iter().filter(move |m| m.t_s <= t + 1e-9)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tl() -> Timeline {
        let ev = [
            r#"{"t_s":24.4,"kind":"docking_state","from":"SOFT_CAPTURE","to":"LATCHED"}"#,
            r#"{"t_s":20.71,"kind":"guarantee_violated","name":"clearance_5cm","margin":-1e-5}"#,
            r#"{"t_s":24.2,"kind":"contact_start","a":"target/slot.back","b":"chaser/cone"}"#,
            r#"{"t_s":20.02,"kind":"docking_state","from":"FREE","to":"ATTRACTING"}"#,
        ];
        let markers = ev
            .iter()
            .map(|s| Marker::from_event(&serde_json::from_str(s).unwrap()).unwrap())
            .collect();
        Timeline::new(0.0, 60.0, 0.1, markers)
    }

    #[test]
    fn invariant_timeline_markers_classified_and_sorted() {
        let t = tl();
        let kinds: Vec<_> = t.markers.iter().map(|m| (m.t_s, m.kind)).collect();
        assert_eq!(
            kinds,
            vec![
                (20.02, MarkerKind::Other),
                (20.71, MarkerKind::Violation),
                (24.2, MarkerKind::Contact),
                (24.4, MarkerKind::Latch),
            ]
        );
        assert_eq!(t.markers[2].label, "contact target/slot.back - chaser/cone");
    }

    #[test]
    fn invariant_timeline_speed_clamped_and_laddered() {
        let mut t = tl();
        assert_eq!(t.speed(), 1.0);
        assert_eq!(t.set_speed(5000.0), MAX_SPEED);
        assert_eq!(t.set_speed(0.01), MIN_SPEED);
        assert_eq!(t.set_speed(f64::NAN), 1.0);
        assert_eq!(t.faster(), 2.0);
        assert_eq!(t.faster(), 5.0);
        assert_eq!(t.slower(), 2.0);
        for _ in 0..30 {
            t.faster();
        }
        assert_eq!(t.speed(), 1000.0);
        for _ in 0..30 {
            t.slower();
        }
        assert_eq!(t.speed(), 0.1);
        // Off-ladder speeds step to the neighbouring rung.
        t.set_speed(3.0);
        assert_eq!(t.faster(), 5.0);
        t.set_speed(3.0);
        assert_eq!(t.slower(), 2.0);
    }

    #[test]
    fn invariant_timeline_advance_is_speed_times_wall_time() {
        let mut t = tl();
        // Paused: wall time does not move it.
        assert_eq!(t.advance(1.0), 0.0);
        t.toggle_play();
        t.set_speed(10.0);
        // 30 frames of 1/60 s at 10× = 5 s simulated.
        for _ in 0..30 {
            t.advance(1.0 / 60.0);
        }
        assert!((t.t_s - 5.0).abs() < 1e-12, "{}", t.t_s);
        t.set_speed(0.1);
        t.advance(2.0);
        assert!((t.t_s - 5.2).abs() < 1e-12);
        // Runs into the end: clamps and pauses.
        t.set_speed(1000.0);
        t.advance(1.0);
        assert_eq!(t.t_s, 60.0);
        assert!(!t.playing);
        // Play again from the end restarts.
        t.toggle_play();
        assert_eq!(t.t_s, 0.0);
        assert!(t.playing);
    }

    #[test]
    fn invariant_timeline_seek_step_and_fraction() {
        let mut t = tl();
        t.seek(-5.0);
        assert_eq!(t.t_s, 0.0);
        t.seek(1e9);
        assert_eq!(t.t_s, 60.0);
        t.seek(f64::NAN);
        assert_eq!(t.t_s, 60.0);
        t.seek_fraction(0.25);
        assert!((t.t_s - 15.0).abs() < 1e-12);
        assert!((t.fraction() - 0.25).abs() < 1e-12);
        t.playing = true;
        t.step(1);
        assert!(!t.playing);
        assert!((t.t_s - 15.1).abs() < 1e-12);
        t.step(-1);
        t.step(-1);
        assert!((t.t_s - 14.9).abs() < 1e-12);
        t.seek_fraction(2.0);
        assert_eq!(t.t_s, 60.0);
    }

    #[test]
    fn invariant_timeline_marker_navigation() {
        let mut t = tl();
        t.seek(20.5);
        assert_eq!(t.next_marker().map(|m| m.kind), Some(MarkerKind::Violation));
        assert_eq!(t.t_s, 20.71);
        assert_eq!(t.next_marker().map(|m| m.kind), Some(MarkerKind::Contact));
        assert_eq!(t.next_marker().map(|m| m.kind), Some(MarkerKind::Latch));
        assert_eq!(t.t_s, 24.4);
        assert!(t.next_marker().is_none());
        assert_eq!(t.t_s, 24.4);
        assert_eq!(t.past_markers().count(), 4);
        assert_eq!(t.prev_marker().map(|m| m.t_s), Some(24.2));
        assert_eq!(t.past_markers().count(), 3);
        t.seek(0.0);
        assert!(t.prev_marker().is_none());
        assert_eq!(t.past_markers().count(), 0);
    }
}
