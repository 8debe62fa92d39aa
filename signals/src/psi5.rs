//! The crush-zone satellites' frames as the ECU's PSI5 receiver hands them on.
//!
//! **The link.** An upfront satellite (e.g. NXP MMA5124: ±240 g, PSI5 v1.3,
//! "PSI5-P10P-500/3L": parallel bus, 10-bit data, even parity, 500 µs synchronous period)
//! answers every sync pulse of the ECU with one frame: a 10-bit two's-complement data word
//! and one even-parity bit. Data words −480 … +480 are acceleration (here ±480 codes span the
//! sensor's ±full scale, + = deceleration as the crash's sign convention is not PSI5's: the
//! satellite is mounted so that a frontal crush reads positive); −512 … −481 and +481 … +511
//! are the protocol's status and error range, of which the bench's satellites use
//! [`SENSOR_DEFECT`].
//!
//! **The record.** [`SatelliteFrames`] carries up to [`SATELLITE_BATCH_CAPACITY`] frames of one
//! satellite with the sample instant of the first, like [`crate::CrashAccelSample`]; each frame
//! is the raw 11 bits (data + parity) in a `u16`, so that a parity error or a corrupt word
//! reaches the ECU as it would on the wire and is counted there ([`decode`]).

/// Largest |data word| that is an acceleration.
pub const DATA_LIMIT: i16 = 480;

/// The status word the bench's satellites send when their self-test fails (inside the
/// protocol's −512 … −481 status range).
pub const SENSOR_DEFECT: i16 = -500;

/// Bit of the even-parity bit above the 10 data bits.
const PARITY_BIT: u16 = 1 << 10;
/// The 10 data bits.
const DATA_MASK: u16 = 0x3FF;

/// Maximum frames in one [`SatelliteFrames`] batch.
pub const SATELLITE_BATCH_CAPACITY: usize = 8;

/// Which satellite: each has its own PSI5 channel and its own service.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[repr(u8)]
pub enum SatelliteSide {
    /// At the left rail tip.
    Left = 0,
    /// At the right rail tip.
    Right = 1,
}

impl SatelliteSide {
    /// Both, left first (the order of every per-satellite array).
    pub const BOTH: [SatelliteSide; 2] = [SatelliteSide::Left, SatelliteSide::Right];
}

/// What one frame says.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Psi5Word {
    /// An acceleration, in data codes (−480 … +480, + = deceleration).
    Data(i16),
    /// A status or error word (|code| > 480).
    Status(i16),
    /// The parity does not match, or bits beyond the 11 of a frame are set.
    Corrupt,
}

/// The frame of data word `code` (clamped to the 10-bit range) with its even parity.
#[inline]
pub fn encode(code: i16) -> u16 {
    let data = (code.clamp(-512, 511) as u16) & DATA_MASK;
    let parity = if data.count_ones() % 2 == 1 {
        PARITY_BIT
    } else {
        0
    };
    data | parity
}

/// The word of `frame`: its data sign-extended from 10 bits, if the parity holds.
#[inline]
pub fn decode(frame: u16) -> Psi5Word {
    if frame & !(DATA_MASK | PARITY_BIT) != 0 || frame.count_ones() % 2 == 1 {
        return Psi5Word::Corrupt;
    }
    let data = frame & DATA_MASK;
    // Sign-extend the 10-bit two's complement.
    let code = ((data << 6) as i16) >> 6;
    if code.abs() > DATA_LIMIT {
        Psi5Word::Status(code)
    } else {
        Psi5Word::Data(code)
    }
}

/// The data code of deceleration `decel_mps2` for a sensor of range `full_scale_mps2`:
/// rounded, clipped at ±[`DATA_LIMIT`] (a saturated satellite reads its range).
#[inline]
pub fn code_of(decel_mps2: f64, full_scale_mps2: f64) -> i16 {
    let lsb = full_scale_mps2 / DATA_LIMIT as f64;
    let x = decel_mps2 / lsb;
    if x.is_nan() {
        return SENSOR_DEFECT;
    }
    let x = if x > DATA_LIMIT as f64 {
        DATA_LIMIT as f64
    } else if x < -(DATA_LIMIT as f64) {
        -(DATA_LIMIT as f64)
    } else {
        x
    };
    // |x| ≤ 480: the cast is exact after rounding half away from zero.
    (if x >= 0.0 { x + 0.5 } else { x - 0.5 }) as i16
}

/// A batch of one satellite's PSI5 frames (raw: data + parity), oldest first.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct SatelliteFrames {
    /// CLOCK_MONOTONIC time of the sample of `frames[0]`, ns.
    pub first_timestamp_ns: u64,
    /// Publisher sequence counter.
    pub sequence: u64,
    /// Time between consecutive samples (the sync period), ns.
    pub sample_period_ns: u32,
    /// Number of valid entries in `frames` (values above capacity are clamped by readers).
    pub count: u32,
    /// The frames: bits 0–9 data, bit 10 even parity.
    pub frames: [u16; SATELLITE_BATCH_CAPACITY],
}

impl SatelliteFrames {
    /// An empty batch.
    pub const EMPTY: Self = Self {
        first_timestamp_ns: 0,
        sequence: 0,
        sample_period_ns: 0,
        count: 0,
        frames: [0; SATELLITE_BATCH_CAPACITY],
    };

    /// The valid frames; a corrupt `count` is clamped, so this never panics.
    #[inline]
    pub fn frames(&self) -> &[u16] {
        let n = (self.count as usize).min(SATELLITE_BATCH_CAPACITY);
        self.frames.get(..n).unwrap_or(&[])
    }
}

impl Default for SatelliteFrames {
    fn default() -> Self {
        Self::EMPTY
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_data_word_round_trips_with_even_parity() {
        for code in -512..=511i16 {
            let f = encode(code);
            assert_eq!(f.count_ones() % 2, 0, "{code}");
            let expected = if code.abs() > DATA_LIMIT {
                Psi5Word::Status(code)
            } else {
                Psi5Word::Data(code)
            };
            assert_eq!(decode(f), expected);
        }
    }

    #[test]
    fn one_flipped_bit_or_a_bit_beyond_the_frame_is_corrupt() {
        for code in [-480i16, -1, 0, 1, 77, 480] {
            for bit in 0..16 {
                assert_eq!(
                    decode(encode(code) ^ (1 << bit)),
                    Psi5Word::Corrupt,
                    "{code} {bit}"
                );
            }
        }
    }

    #[test]
    fn codes_are_rounded_and_clipped_at_the_range() {
        let fs = 240.0 * 9.806_65;
        assert_eq!(code_of(0.0, fs), 0);
        assert_eq!(code_of(fs / 480.0 * 10.4, fs), 10);
        assert_eq!(code_of(-fs / 480.0 * 10.6, fs), -11);
        assert_eq!(code_of(2.0 * fs, fs), 480);
        assert_eq!(code_of(-2.0 * fs, fs), -480);
        assert_eq!(code_of(f64::NAN, fs), SENSOR_DEFECT);
    }
}
