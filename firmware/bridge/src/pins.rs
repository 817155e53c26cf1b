//! The bridge's pin map, by RP2350B GPIO number: the one place it is
//! written down. The RP2350 image, the board twin, `docs/bridge-hardware.md`
//! and the schematic in `hardware/` (checked by a test against this module)
//! all follow it.
//!
//! GPIO 28-31 are free. GPIO 47 is left to the PGA2350's PSRAM, whose chip
//! select it is ([`VSEL`]).

/// D0-D7 of the chip's bus, through the 74LVC8T245's A side (GPIO 0-7).
pub const D0: u32 = 0;
/// A0 (high: the command register on a write, status on a read).
pub const A0: u32 = 8;
/// CS*.
pub const CS: u32 = 9;
/// DIR of the 74LVC8T245 (high: bridge to chip).
pub const SHIFT_DIR: u32 = 10;
/// RD*.
pub const RD: u32 = 11;
/// WR*.
pub const WR: u32 = 12;
/// The bus player's OUT pins: GPIO 0-12.
pub const BUS_COUNT: u32 = 13;

/// The chip's inputs, in `ppmc_core::protocol::Input::ALL`'s order:
/// L1*..L4*, ALM*, CNP*, AUXI0..3 (GPIO 13-22), through the 74AHCT244s.
pub const INPUTS: [u32; 10] = [13, 14, 15, 16, 17, 18, 19, 20, 21, 22];
/// RESET* of the chip, through a 74AHCT244.
pub const RESET: u32 = 23;
/// OE* of the 74LVC245s that bring the chip's outputs in (pulled up: the
/// chip's outputs are cut off until the firmware pulls it low). High
/// during the self-test, so that the test generator drives the capture
/// inputs instead of the chip.
pub const CAPTURE_OE: u32 = 24;
/// The self-test generator: through a 74LVC2G126's two buffers, each with
/// 1 kOhm, onto the capture inputs of POUT and INT* (the bridge side of the
/// 74LVC245); the buffers are on only while [`CAPTURE_OE`] is high, so that
/// nothing joins the two capture nets while the capture runs. Pulled down:
/// undriven, it puts a low on them.
pub const TEST_GEN: u32 = 25;
/// Enables the 74AHCT244s' outputs towards the chip (through an N-MOSFET on
/// their OE*, pulled down at this pin): low while the bridge boots or is
/// unpowered, when pull-ups and pull-downs on the chip side hold RESET*
/// low and L1*..L4*, ALM*, CNP* released.
pub const DRIVE_EN: u32 = 26;

/// POUT, stamped on its rising edges with DIR.
pub const POUT: u32 = 32;
/// DIR, read with each POUT edge (and sampled).
pub const DIR: u32 = 33;
/// INT*, stamped on both edges.
pub const INT: u32 = 34;
/// HOLD, stamped on both edges.
pub const HOLD: u32 = 35;
/// AUX*, stamped on both edges.
pub const AUX: u32 = 36;
/// S1..S5, sampled (GPIO 37-41).
pub const S: [u32; 5] = [37, 38, 39, 40, 41];
/// AUXO0..3, sampled (GPIO 42-45).
pub const AUXO: [u32; 4] = [42, 43, 44, 45];
/// The capture inputs that nothing drives during the self-test, when the
/// 74LVC245s' outputs are off (POUT's and INT*'s are the generator's):
/// pulled up meanwhile, so that they hold still (a floating input drifts,
/// RP2350-E9; both the image and the board twin pull them).
pub const SELF_TEST_PULLED: [u32; 12] = [
    DIR, HOLD, AUX, S[0], S[1], S[2], S[3], S[4], AUXO[0], AUXO[1], AUXO[2], AUXO[3],
];

/// The CSEL strap, sensed at boot through a spare channel of the
/// 74LVC245 (GPIO 46 is an ADC pin of the RP2350B, not 5 V tolerant).
pub const CSEL: u32 = 46;
/// The VSEL strap, sensed at boot through the 74LVC245's other spare
/// channel. Not on GPIO 47: the PGA2350 wires GPIO 47 to its PSRAM's chip
/// select (the RP2350's QMI CS1n), and a strap there would select the
/// PSRAM while the RP2350 reads its flash. GPIO 27 is a digital pin (the
/// RP2350B's ADC pins are 40-47) in GPIO bank 0: the image reads it from
/// SIO GPIO_IN, not GPIO_HI_IN.
pub const VSEL: u32 = 27;

/// S1..S5, AUXO0..3 and DIR, the outputs the CPU samples, as bits of
/// GPIO 32-47 (bit 0: GPIO 32; the board code's `Hal::read_high_pins`, the
/// image's GPIO_HI_IN).
pub const SAMPLED_HIGH: u16 = {
    let mut m = 1 << (DIR - 32);
    let mut i = 0;
    while i < S.len() {
        m |= 1 << (S[i] - 32);
        i += 1;
    }
    let mut i = 0;
    while i < AUXO.len() {
        m |= 1 << (AUXO[i] - 32);
        i += 1;
    }
    m
};
