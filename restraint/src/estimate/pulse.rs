//! The predicted pulse the diagnostics record carries, filled a chunk per cycle.
//!
//! Why chunks: the 64 diagnostics points cost ≈ 3 200 instructions when sampled in one go
//! (≈ 40 per point from the closed-form solution, ≈ 300 more for each crush-curve segment the
//! points enter), more than half of the whole worst-case cycle's budget (6 000) — for a
//! picture nobody acts on within the cycle. The prediction itself (the summary: Δv, a_max,
//! a_mean, contact duration) is complete in the cycle that makes it; the pulse follows from a
//! kept [`SampleCursor`] (no re-entry cost) in the cycles *without* a new object sample (they
//! run no filter, prediction or LUT query), [`POINTS_PER_CYCLE`] points or
//! [`ENTRIES_PER_CYCLE`] segment entries per cycle, whichever comes first — ≈ 1 000
//! instructions at most. A 64-point pulse over a ten-segment crush curve is complete after 8–9
//! such cycles, i.e. before the next sample of a 10 ms object list. In CRASH and POST-CRASH nothing is filled (those cycles belong to
//! the crash confirmation). The record always says how many points are valid
//! (`pulse_points`); a newer prediction restarts the fill. Fewer points or a lower rate were
//! the alternatives: fewer points lose the pulse's shape (64 points over 150 ms are 2.3 ms
//! apart, the peak of a 70 ms pulse is ~10 ms wide), a lower rate bounds nothing (the cycle
//! that fills still pays in full).

use physics::{defaults::PULSE_DURATION_S, ExactCollision, SampleCursor};

use crate::signals::PULSE_POINTS;

/// Points sampled per cycle.
pub const POINTS_PER_CYCLE: usize = 10;

/// Segment entries per cycle (an entry costs ≈ 300 instructions, a plain point ≈ 40).
pub const ENTRIES_PER_CYCLE: usize = 2;

/// Time between two diagnostics points, s (the 150 ms prediction window over 64 points).
pub const PULSE_DT_S: f64 = PULSE_DURATION_S / PULSE_POINTS as f64;

/// The diagnostics pulse of the newest prediction, as far as it is filled.
#[derive(Debug, Clone)]
pub(crate) struct DiagnosticsPulse {
    /// Ego acceleration, m/s², at k · [`PULSE_DT_S`] after contact; zero beyond `filled`.
    points: [f32; PULSE_POINTS],
    filled: usize,
    cursor: Option<SampleCursor>,
}

impl DiagnosticsPulse {
    pub(crate) const fn new() -> Self {
        Self {
            points: [0.0; PULSE_POINTS],
            filled: 0,
            cursor: None,
        }
    }

    /// A new prediction was made: fill from its first point on.
    pub(crate) fn restart(&mut self) {
        self.points = [0.0; PULSE_POINTS];
        self.filled = 0;
        self.cursor = SampleCursor::new(PULSE_DT_S).ok();
    }

    /// No prediction: no points.
    pub(crate) fn clear(&mut self) {
        self.points = [0.0; PULSE_POINTS];
        self.filled = 0;
        self.cursor = None;
    }

    /// Samples the next chunk of `sol` (the prediction this fill was restarted for): up to
    /// [`POINTS_PER_CYCLE`] points, with at most [`ENTRIES_PER_CYCLE`] segment entries (the
    /// expensive step).
    #[inline(always)]
    pub(crate) fn fill(&mut self, sol: &ExactCollision) {
        let Some(cursor) = self.cursor.as_mut() else {
            return;
        };
        let end = (self.filled + POINTS_PER_CYCLE).min(PULSE_POINTS);
        let mut entries = 0;
        for p in self.points.iter_mut().take(end).skip(self.filled) {
            if cursor.next_enters(sol) {
                if entries == ENTRIES_PER_CYCLE {
                    break;
                }
                entries += 1;
            }
            *p = cursor.next(sol).ego_accel_mps2 as f32;
            self.filled += 1;
        }
        if self.filled >= PULSE_POINTS {
            self.cursor = None;
        }
    }

    /// All points (valid up to [`Self::filled`], zero after).
    pub(crate) fn points(&self) -> &[f32; PULSE_POINTS] {
        &self.points
    }

    /// Valid points.
    pub(crate) fn filled(&self) -> usize {
        self.filled
    }
}
