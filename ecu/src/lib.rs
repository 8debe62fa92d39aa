//! The restraint ECU's process shell.
//!
//! The restraint logic is the `no_std` core [`restraint`] (its own crate, so the compiler keeps
//! it free of the operating system). This crate is everything around it:
//!
//! * [`runtime`] — absolute-deadline loop on CLOCK_MONOTONIC, RT settings (SCHED_FIFO,
//!   mlockall, pinning, PM-QoS), preallocated timing histograms, the timing report,
//!   configuration, the iceoryx2 com layer and the `monitor` command. It knows nothing about
//!   restraints: it runs any [`restraint::Activity`] through [`restraint::CycleIo`].
//! * [`can_port`] — the SocketCAN [`runtime::CanPort`] over `bus::socket::BusSocket`.
//! * [`lut_input`] — what the shell loaded, handed to the core as a
//!   borrowed view and plain numbers.

pub mod runtime;

#[cfg(feature = "shell")]
pub mod can_port;

/// The loaded characteristic diagram as the core takes it: the borrowed view plus the header
/// facts it checks (ego vehicle, the planning margin the cells are verified for) and reports
/// (LUT id).
pub fn lut_input(d: &diagram::Diagram) -> restraint::Lut<'_> {
    restraint::Lut {
        view: d.view(),
        id: d.lut_id(),
        ego_mass_kg: d.header().ego.mass_kg,
        ego_class: d.header().ego.class,
        // An unreadable span: NaN, which the core rejects.
        lighter_opponent_kg: d
            .header()
            .lighter_opponent_span_kg()
            .map_or(Some(f32::NAN), |s| s.map(|kg| kg as f32)),
    }
}
