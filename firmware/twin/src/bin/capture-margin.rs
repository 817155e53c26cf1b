//! The capture's margin at the chip's fastest pulse rate, measured on the
//! board twin (docs/performance.md):
//!
//! ```sh
//! cargo run --release --locked --manifest-path firmware/Cargo.toml -p ppmc-twin --bin capture-margin
//! ```
//!
//! A binary of the twin's crate, so that it is built with the twin, from
//! the same release build of the board code.

fn main() -> std::process::ExitCode {
    let m = match ppmc_bridge_fw::twin::capture_margin() {
        Ok(m) => m,
        Err(e) => {
            eprintln!("capture-margin: {e}");
            return std::process::ExitCode::FAILURE;
        }
    };
    println!(
        "RP2350 at {} MHz, chip at 40 MHz: {} pulses {} ns apart ({:.0} kpps)",
        m.sysclk_hz / 1_000_000,
        m.pulses,
        m.interval_ns,
        1e6 / m.interval_ns as f64
    );
    println!(
        "POUT ring: {} words deep (its DMA ring), at most {} waiting when drained; longest gap between drains {} ns",
        m.depth, m.fullest, m.longest_gap_ns
    );
    println!(
        "margin: {:.1}x (ring depth in pulse intervals over the longest gap); capture lost: {}",
        m.margin(),
        m.lost
    );
    std::process::ExitCode::SUCCESS
}
