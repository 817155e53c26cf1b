//! The host firmware's rules of chapter 3, judged from captures made for
//! each (issue 30, `docs/capture.md`): a hand-written bus capture, or a
//! suite scenario that misuses the chip on purpose, exported with its bus
//! as a logic analyzer records it. Each gives its finding, under its
//! section, while the board itself passes; a correct host's capture gives
//! none.

use ppmc::emu::{Board, ModelConfig};
use ppmc::protocol::Straps;
use ppmc::time::Instant;
use ppmc::vcd_export::{export_with, Export};
use ppmc_capture::judge::{judge, CaptureVerdict, JudgeOptions, Judgement};
use ppmc_logic::map::ChannelMap;
use ppmc_logic::source::LogicSource;
use ppmc_logic::vcd::VcdReader;
use std::path::Path;

/// A bus access of a hand-written capture.
#[derive(Clone, Copy)]
enum Bus {
    /// Write command register (A0 high).
    Wc(u8),
    /// Write data register (A0 low).
    Wd(u8),
    /// Read status register: the byte the chip drives.
    Rs(u8),
    /// Read data register.
    Rd(u8),
}

/// The pulses the model puts out for the host's `cycles`, until `end_us`:
/// what a board that passes shows on POUT (each pulse's time in ns).
fn model_pulses(cycles: &[(u64, Bus)], end_us: u64) -> Vec<u64> {
    let mut b = Board::new(Straps::default(), ModelConfig::default()).expect("model");
    for &(us, access) in cycles {
        b.advance_to(Instant::from_nanos(us * 1000));
        match access {
            Bus::Wc(x) => b.write_command(x),
            Bus::Wd(x) => b.write_data(x),
            Bus::Rs(_) => {}
            Bus::Rd(_) => {
                b.read_data();
            }
        }
    }
    b.advance_to(Instant::from_nanos(end_us * 1000));
    b.record()
        .runs
        .iter()
        .flat_map(|r| (0..r.count).map(|k| r.at(k).as_nanos()))
        .collect()
}

/// A VCD of the bus by hand: each access a 100 ns strobe ending at its
/// time in microseconds (CS* 50 ns before and 20 ns after it); POUT
/// pulses 1 us wide where the model pulses; the capture ends at `end_us`.
fn hand_vcd(cycles: &[(u64, Bus)], end_us: u64) -> String {
    let wires = [
        "cs", "rd", "wr", "a0", "d0", "d1", "d2", "d3", "d4", "d5", "d6", "d7", "pout",
    ];
    let mut v = String::from("$timescale 1 ns $end\n$scope module bus $end\n");
    let code = |i: usize| char::from(b'!' + u8::try_from(i).expect("few wires"));
    for (i, w) in wires.iter().enumerate() {
        v.push_str(&format!("$var wire 1 {} {w} $end\n", code(i)));
    }
    v.push_str("$upscope $end\n$enddefinitions $end\n#0\n$dumpvars\n");
    for (i, w) in wires.iter().enumerate() {
        let idle = matches!(*w, "cs" | "rd" | "wr");
        v.push_str(&format!("{}{}\n", u8::from(idle), code(i)));
    }
    v.push_str("$end\n");
    // (ns, wire, level), put in time order below.
    let mut changes: Vec<(u64, usize, bool)> = Vec::new();
    let wire = |w: &str| wires.iter().position(|x| *x == w).expect("a bus wire");
    for &(us, access) in cycles {
        let t = us * 1000;
        let (strobe, a0, byte) = match access {
            Bus::Wc(b) => ("wr", true, b),
            Bus::Wd(b) => ("wr", false, b),
            Bus::Rs(b) => ("rd", true, b),
            Bus::Rd(b) => ("rd", false, b),
        };
        changes.push((t - 150, wire("cs"), false));
        changes.push((t - 150, wire("a0"), a0));
        changes.push((t - 100, wire(strobe), false));
        for b in 0..8 {
            changes.push((t - 100, wire(&format!("d{b}")), byte >> b & 1 == 1));
        }
        changes.push((t, wire(strobe), true));
        changes.push((t + 20, wire("cs"), true));
    }
    for p in model_pulses(cycles, end_us) {
        changes.push((p, wire("pout"), true));
        changes.push((p + 1000, wire("pout"), false));
    }
    changes.sort_by_key(|c| c.0);
    let mut now = None;
    for (t, w, level) in changes {
        if now != Some(t) {
            v.push_str(&format!("#{t}\n"));
            now = Some(t);
        }
        v.push_str(&format!("{}{}\n", u8::from(level), code(w)));
    }
    v.push_str(&format!("#{}\n", end_us * 1000));
    v
}

fn judged_vcd(text: &[u8]) -> Judgement {
    let mut cap = VcdReader::new(text, Path::new("hand.vcd")).expect("a VCD header");
    let map = ChannelMap::from_names(cap.info()).expect("the chip's names");
    judge(&mut cap, &map, &JudgeOptions::default()).expect("judged")
}

fn judged_hand(cycles: &[(u64, Bus)], end_us: u64) -> Judgement {
    judged_vcd(hand_vcd(cycles, end_us).as_bytes())
}

/// Suite scenario `name`, run on the clean model with a bus cycle per
/// access, exported with its bus (`ppmc export --scenario --bus`) and
/// judged.
fn judged_scenario(name: &str) -> Judgement {
    let suite = ppmc_scenarios::all();
    let s = suite.iter().find(|s| s.name == name).expect("scenario");
    let (trace, _) =
        ppmc_capture::fault_matrix::capture::analyzer_trace(&ModelConfig::default(), s)
            .expect("a capture");
    let mut buf = Vec::new();
    let export = Export {
        window: None,
        bus: true,
    };
    export_with(&trace, export, &mut buf).expect("export");
    judged_vcd(&buf)
}

/// The board passed, and the host's findings are under `sections`, in
/// order; each message contains `says`.
fn assert_host(j: &Judgement, sections: &[&str], says: &str) {
    assert_eq!(j.verdict, CaptureVerdict::Passed, "the board: {j:?}");
    let got: Vec<&str> = j.host.iter().map(|h| h.section).collect();
    assert_eq!(got, sections, "{:#?}", j.host);
    for h in &j.host {
        assert!(h.what.contains(says), "{h:?}");
    }
}

/// 3-1-1 (2): a data byte written 1 us after the initialization command,
/// while IBF is still 1, replaces the command.
#[test]
fn s3_1_1_a_byte_written_while_ibf_is_1() {
    let j = judged_hand(&[(1, Bus::Wc(0x02)), (2, Bus::Wd(0x64))], 30);
    // The data byte replaced the command, and the chip then took a data
    // byte no command asked for: error 3 (3-1-4).
    assert_host(&j, &["3-1-1", "3-1-4"], "");
    assert!(j.host[0].what.contains("written while IBF was 1"), "{j:?}");
}

/// 3-1-1 (1), 3-1-2: a data read while OBF is 0 reads nothing valid.
#[test]
fn s3_1_2_a_data_read_before_obf() {
    let j = judged_hand(&[(1, Bus::Rs(0x00)), (2, Bus::Rd(0x00))], 10);
    assert_host(&j, &["3-1-1"], "before OBF was 1");
}

/// 3-2: "This command must be issued first after the system is turned on
/// or reset": a single step before any initialization, which the chip
/// answers with error 2 (Table 3-2).
#[test]
fn s3_2_a_move_before_initialization() {
    // 0x42: single step CW; the chip takes it 6 us later: error 2.
    let j = judged_hand(&[(1, Bus::Wc(0x42)), (21, Bus::Rs(0xA0))], 50);
    assert_host(&j, &["3-2"], "error 2");
    assert_eq!(j.host[0].at_ps, 1_000_000, "at the write");
}

/// 3-1-4: data "are written after each command code is written": a data
/// byte with no command before it is error 3 (Table 3-2).
#[test]
fn s3_1_4_a_data_byte_no_command_asked_for() {
    let j = judged_hand(&[(1, Bus::Wd(0x12)), (21, Bus::Rs(0xB0))], 50);
    assert_host(&j, &["3-1-4"], "error 3");
}

/// 3-1-4 and 3-1-1 (4): a command code written while bits 6-4 still count
/// three initialization bytes due; the chip drops the initialization
/// (notes N35) and reads the input signals instead.
#[test]
fn s3_1_4_a_command_abandons_one_still_awaiting_parameters() {
    let j = judged_hand(
        &[
            (1, Bus::Wc(0x02)),
            (21, Bus::Rs(0x40)),
            (30, Bus::Wd(100)),
            (50, Bus::Rs(0x30)),
            (60, Bus::Wc(0x81)),
            (100, Bus::Rs(0x01)),
            (110, Bus::Rd(0x3F)),
            (130, Bus::Rs(0x00)),
        ],
        200,
    );
    assert_host(&j, &["3-1-4"], "still awaited 3 parameter bytes");
    assert_eq!(j.host[0].at_ps, 60_000_000);
}

/// 3-3-1 and 3-3-2: the stop commands have effect only while BUSY is 1;
/// while the motor is stopped the chip answers error 0.
#[test]
fn s3_3_1_a_stop_while_the_motor_is_stopped() {
    let j = judged_hand(&[(1, Bus::Wc(0x40)), (21, Bus::Rs(0x80))], 50);
    assert_host(&j, &["3-3-1"], "error 0");
    let j = judged_hand(&[(1, Bus::Wc(0x41)), (21, Bus::Rs(0x80))], 50);
    assert_host(&j, &["3-3-2"], "error 0");
}

/// Table 3-2 error 0: an undefined command code (0x87).
#[test]
fn table_3_2_an_undefined_command_code() {
    let j = judged_hand(&[(1, Bus::Wc(0x87)), (21, Bus::Rs(0x80))], 50);
    assert_host(&j, &["Table 3-2"], "does not define");
}

/// 3-2-2: "255 > RL > RH > 0 ... Error #5 will be returned": an
/// initialization with RH above RL.
#[test]
fn s3_2_2_initialization_data_out_of_bounds() {
    let j = judged_hand(
        &[
            (1, Bus::Wc(0x02)),
            (21, Bus::Wd(20)),
            (41, Bus::Wd(100)),
            (61, Bus::Wd(4)),
            (81, Bus::Wd(0)),
            (101, Bus::Rs(0xD0)),
        ],
        150,
    );
    assert_host(&j, &["3-2-2"], "error 5");
    assert_eq!(j.host[0].at_ps, 81_000_000, "at the last byte");
}

/// 3-1-1 (3): while BUSY is 1 only Immediate Stop, Decelerating Stop and
/// AUX ON/OFF are accepted: an operation command then is error 1.
#[test]
fn s3_1_1_a_command_while_busy() {
    let j = judged_scenario("e1_operation_command_while_busy");
    assert_host(&j, &["3-1-1 (3)"], "error 1");
}

/// 3-4: "Data can be read only when the motor is stopped": a register read
/// command while BUSY is 1 is error 1.
#[test]
fn s3_4_a_register_read_while_busy() {
    let j = judged_scenario("e1_register_read_while_busy");
    assert_host(&j, &["3-4"], "error 1");
}

/// 3-1-1 (3): "Other command codes and data are not accepted" while BUSY
/// is 1: a data byte then is error 6.
#[test]
fn s3_1_1_a_data_byte_while_busy() {
    let j = judged_scenario("e6_data_while_busy");
    assert_host(&j, &["3-1-1 (3)"], "error 6");
}

/// 3-3-2: "If this command is received during deceleration, Error #7 will
/// be returned": a Decelerating Stop written while a 400-step move
/// decelerates to its end (pulses 300 to 399, PA 100).
#[test]
fn s3_3_2_a_decelerating_stop_while_decelerating() {
    // 4-phase, RL 100, RH 20, PA 100; at 30 ms a 400-step accel move.
    let mut cycles = vec![
        (1, Bus::Wc(0x02)),
        (21, Bus::Wd(100)),
        (41, Bus::Wd(20)),
        (61, Bus::Wd(100)),
        (81, Bus::Wd(0)),
        (30_000, Bus::Wc(0x43)),
        (30_020, Bus::Wd(0x8F)),
        (30_040, Bus::Wd(0x01)),
        (30_060, Bus::Wd(0x00)),
    ];
    let pulses = model_pulses(&cycles, 200_000);
    assert_eq!(pulses.len(), 400, "the move alone");
    let stop = pulses[320] / 1000 + 5;
    cycles.extend([(stop, Bus::Wc(0x41)), (stop + 20, Bus::Rs(0xF4))]);
    let j = judged_hand(&cycles, 200_000);
    assert_host(&j, &["3-3-2"], "error 7");
    assert_eq!(j.pulses, 400, "the stop changed nothing");
}

/// 3-5-4: software reset "is effective only when the motor is stopped. If
/// this command is issued during motor operation, the command will be
/// mistaken for the AUX* ON command."
#[test]
fn s3_5_4_a_software_reset_while_busy() {
    let j = judged_scenario("s3_5_4_software_reset_while_busy_is_aux_on");
    assert_host(&j, &["3-5-4"], "AUX ON");
}

/// Chapter 3's flowcharts kept (IBF and BUSY checked before each write,
/// OBF before each read, every parameter byte written): moves (3-3),
/// register reads (3-4), initialization and software reset (3-2, 3-5-4)
/// and the auxiliary commands (3-5) give no host finding.
#[test]
fn a_correct_hosts_captures_give_no_finding() {
    for name in [
        "s3_3_5_constant_speed_100_steps",
        "s3_3_4_accel_1000_steps_cw",
        "s3_4_1_finish_read_releases_int",
        "s3_5_4_recovery_after_software_reset",
        "s3_5_3_aux_output_drives_auxo",
    ] {
        let j = judged_scenario(name);
        assert_eq!(j.verdict, CaptureVerdict::Passed, "{name}: {j:?}");
        assert!(j.accesses > 5, "{name}: {j:?}");
        assert!(j.host.is_empty(), "{name}: {:#?}", j.host);
    }
}
