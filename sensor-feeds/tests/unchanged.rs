//! The safing accelerometer and `[[accel_event]]` changed nothing that was there before: every
//! library file's object list, crash accelerometer batches and CAN frames are bit for bit what
//! the player produced before them (fingerprints recorded with the player of commit b849bea,
//! before the safing sensor existed). The accelerometers low-pass their input
//! before sampling (`world::lowpass`, on by default): these fingerprints are taken with it off
//! (`accel_lowpass_hz = 0`), the ideal sampler of the model they were recorded with — so
//! everything *else* is still bit for bit as it was.

use sensor_feeds::{Player, TickOutput};
use std::fmt::Write;
use std::path::PathBuf;
use world::{Scenario, Truth};

/// FNV-1a (64 bit) over the `Debug` text of every record of a whole run (`{:?}` prints each
/// float in its shortest round-tripping form: equal text is equal bits).
fn fingerprint(s: &Scenario) -> u64 {
    let mut player = Player::new(Truth::new(s).expect("truth"), 1_000, 1.0, 0);
    let mut out = TickOutput::default();
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    let mut text = String::new();
    for tick in 0..=(s.duration_s * 1e3).round() as u64 {
        player.tick(tick, &mut out).expect("tick");
        text.clear();
        for o in &out.objects {
            let _ = write!(text, "{o:?}");
        }
        for a in &out.accel {
            let _ = write!(text, "{a:?}");
        }
        for f in &out.can {
            let _ = write!(text, "{f:?}");
        }
        for b in text.bytes() {
            h = (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3);
        }
    }
    h
}

fn load(name: &str) -> Scenario {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(format!("../scenarios/{name}.toml"));
    let mut s = Scenario::load(path).expect("load");
    s.sensor.accel_lowpass_hz = 0.0;
    s
}

/// Fingerprints of the library as it was at commit b849bea, recorded there with this file's
/// [`fingerprint`].
const BEFORE_SAFING: &[(&str, u64)] = &[
    ("accel-dead-before-crash", 0x22f64125d2b1b841),
    ("accel-stuck-before-crash", 0xe9977dc4d4ecb1e5),
    ("avoided-last-moment", 0x2848c7208a47d3c0),
    ("barrier-16-objects-dead", 0x63438c93f6659a39),
    ("barrier-35-objects-dead", 0xcf2102400d97fef8),
    ("fmvss208-48-unbelted", 0x099f763bfda733e9),
    ("fmvss208-56-belted", 0x513f83fcbac34de5),
    ("low-speed-no-fire", 0x67658ee9ee0de990),
    ("low-speed-objects-dead", 0x185e9cfa727fda5c),
    ("mass-overestimated-1200kg", 0x8e480d3e59976eae),
    ("mass-sweep-1000kg", 0x29be43d46c74fc65),
    ("mass-sweep-1300kg", 0xf7fdac5468d218f5),
    ("mass-sweep-2200kg", 0xb772601aef28adc9),
    ("mass-sweep-2800kg", 0x2e60aee007959733),
    ("mass-underestimated-1200kg", 0xf22361c43f49653f),
    ("noisy-mass-estimate", 0xbaf057e9882abea7),
    ("occupant-heavy-110kg", 0x7195809486b366ea),
    ("occupant-light-45kg", 0xb9356561f503cea9),
    ("sensor-dropout", 0x6676914b9ea8c014),
    ("speed-overestimated", 0xd8ce05f62e69b1de),
    ("speed-underestimated", 0xad3f27021aea6333),
    ("taurus-31-31-abs-eba", 0x1e170654d5a47a64),
    ("taurus-48-48-abs", 0xe11afdc9f79e2e8b),
    ("taurus-52-52-none", 0x86b156a9dac2a296),
    ("unbelted-48-48", 0xe5798d54e3b492a5),
];

#[test]
fn the_library_plays_bit_for_bit_as_before_the_safing_sensor() {
    for (name, want) in BEFORE_SAFING {
        let s = load(name);
        assert!(s.accel_events.is_empty(), "{name}");
        assert_eq!(
            fingerprint(&s),
            *want,
            "{name}: objects, crash accelerometer or CAN changed"
        );
    }
}

#[test]
fn a_library_file_plays_the_same_crash_sensor_whatever_the_safing_sensor_does() {
    let mut s = load("taurus-48-48-abs");
    let want = fingerprint(&s);
    s.sensor.safing_rate_hz = 8000.0;
    s.sensor.safing_noise_mps2 = 20.0;
    s.sensor.safing_full_scale_g = 10.0;
    s.sensor.dropouts.push(world::scenario::Dropout {
        start_s: 1.0,
        end_s: 1.5,
        target: world::scenario::DropoutTarget::Safing,
    });
    s.accel_events.push(world::scenario::AccelEvent {
        kind: world::scenario::AccelEventKind::Spike,
        start_s: 1.6,
        peak_g: Some(40.0),
        duration_ms: None,
        frequency_hz: None,
        net_dv_mps: None,
        phase_deg: None,
        rms_g: None,
        end_s: None,
        sensor: world::scenario::EventSensor::Safing,
    });
    s.validate().expect("valid");
    assert_eq!(fingerprint(&s), want);
}
