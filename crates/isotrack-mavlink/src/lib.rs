//! # isotrack-mavlink
//!
//! The MAVLink 2 bridge, at the edge of the workspace (the `no_std` core and its laws know
//! nothing of MAVLink): [`sitl`] plays a scenario's vehicle, field and sensor as a MAVLink
//! vehicle; [`fly`] is the companion computer that flies the scenario's law on the measurements
//! it receives; [`wire`] is what the numbers become on the wire; [`mirror`] runs a scenario in
//! process with the same rounding, the reference a lockstep flight must reproduce bit for bit.
//! Framing, checksums and the common dialect are the `mavlink` crate's; [`link`] owns the UDP
//! socket.
#![deny(missing_docs)]

pub mod fly;
pub mod geo;
pub mod link;
pub mod mirror;
pub mod modes;
pub mod record;
pub mod setpoint;
pub mod sitl;
pub mod vehicle_state;
pub mod wire;

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

static INTERRUPTED: AtomicBool = AtomicBool::new(false);

extern "C" fn on_interrupt(_: libc::c_int) {
    INTERRUPTED.store(true, Ordering::SeqCst);
}

/// A flag that Ctrl-C (SIGINT), SIGTERM and SIGHUP (the terminal closed) set instead of killing the process, so that `fly`
/// and `sitl` stop cleanly (the companion commands its failsafe mode first). A thread copies it
/// into the returned flag every 50 ms, again after each signal (whoever clears the flag hears the
/// next one).
pub fn interrupt_flag() -> Arc<AtomicBool> {
    // SAFETY: the handler only stores to an atomic (async-signal-safe).
    unsafe {
        libc::signal(
            libc::SIGINT,
            on_interrupt as *const () as libc::sighandler_t,
        );
        libc::signal(
            libc::SIGTERM,
            on_interrupt as *const () as libc::sighandler_t,
        );
        // The terminal closing (SIGHUP) stops the same way: never a vehicle left with nobody.
        libc::signal(
            libc::SIGHUP,
            on_interrupt as *const () as libc::sighandler_t,
        );
    }
    let flag = Arc::new(AtomicBool::new(false));
    let f = flag.clone();
    std::thread::spawn(move || loop {
        // Every signal sets the flag again (a second one ends the failsafe's retries).
        if INTERRUPTED.swap(false, Ordering::SeqCst) {
            f.store(true, Ordering::SeqCst);
        }
        std::thread::sleep(std::time::Duration::from_millis(50));
    });
    flag
}
