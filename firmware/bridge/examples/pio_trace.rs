//! Traces the bridge's PIO programs on the twin's PIO model, cycle by
//! cycle, for a second opinion: `firmware/pioemu/crosscheck.py` runs the
//! same words in `pioemu` (PyPI `rp2040-pio-emulator`) on the same stimulus
//! and compares (firmware/README.md, "A second opinion: pioemu").
//!
//! ```sh
//! cargo run -q --locked -p ppmc-bridge-fw --features twin --example pio_trace -- OUT.json
//! ```
//!
//! Each program runs as the firmware assembles and configures it
//! ([`programs`], [`pioregs`]), alone on its state machine. Every pin
//! number in the output is relative to the block's GPIOBASE window (bit
//! `i` is GPIO `GPIOBASE + i`): pioemu knows 32 pins, the window. Per
//! trace cycle `k` (the `k`-th cycle the state machine runs):
//!
//! - `tx`: `[k, word]`, the CPU's writes to the TX FIFO before cycle `k`
//!   (one a cycle, only when the FIFO has room, as the board code does);
//! - `stimulus`: `[k, levels, driven]`, what the outside drives from cycle
//!   `k` on, a function of time only. It has driven the same since before
//!   cycle 0 (the synchroniser is full of it when the machine starts);
//! - `out`, `oe`: the block's output level and enable registers after
//!   cycle `k`; `pc`, `x`: the machine's after cycle `k`;
//! - `rx`: `[k, word]`, words pushed on cycle `k` (read at once, so the RX
//!   FIFO never fills); `pulled`: `[k, word]`, words a `pull` took.

use pio::{Instruction, InstructionOperands};
use ppmc_bridge_fw::bus_cycle::{self, BusTiming, Cycle};
use ppmc_bridge_fw::pioregs::{self, block, SmRegs};
use ppmc_bridge_fw::programs::{self, Loaded};
use ppmc_bridge_fw::twin::pio::{Inputs, World};
use std::collections::VecDeque;
use std::fmt::Write as _;

/// Cycles the outside drives its first levels before the machine starts.
const WARMUP: u64 = 3;

/// One program on one state machine and what it is given.
struct Run<'a> {
    name: &'a str,
    block: usize,
    sm: usize,
    program: &'a Loaded,
    regs: SmRegs,
    /// X at start, when not the configured value.
    x: Option<u32>,
    /// Output levels and enables (window) the firmware forces at start.
    pins: Option<(u32, u32)>,
    cycles: usize,
    /// Window levels and drive of the outside at trace cycle `k`.
    outside: &'a dyn Fn(usize) -> (u32, u32),
    /// TX FIFO words, each with the first cycle the CPU may write it.
    tx: Vec<(usize, u32)>,
}

fn list(v: impl IntoIterator<Item = impl std::fmt::Display>) -> String {
    let items: Vec<String> = v.into_iter().map(|i| i.to_string()).collect();
    format!("[{}]", items.join(","))
}

fn pairs(v: &[(usize, u32)]) -> String {
    list(v.iter().map(|(k, w)| format!("[{k},{w}]")))
}

fn trace(r: &Run) -> String {
    let base = block::GPIOBASE[r.block];
    let words = r.program.words();
    let mut w = World::with_program(r.block, base, words, r.sm, &r.regs);
    // Stopped while the outside's levels fill the synchroniser.
    w.write_ctrl(r.block, 0);
    if let Some(x) = r.x {
        w.blocks[r.block].sm[r.sm].set_x(x);
    }
    if let Some((levels, dirs)) = r.pins {
        let all = u64::from(u32::MAX) << base;
        w.blocks[r.block].force_pins(all, u64::from(levels) << base, u64::from(dirs) << base);
    }
    let start = WARMUP;
    let mut outside = Inputs(|c: u64, _, _| {
        let k = c.saturating_sub(start) as usize;
        let (levels, driven) = (r.outside)(k);
        (u64::from(levels) << base, u64::from(driven) << base)
    });
    w.cpu_wrote(&mut outside);
    while w.cycle < start {
        w.step(&mut outside);
    }
    let initial = w.driven();
    w.write_ctrl(r.block, 1 << r.sm);

    let window = |v: u64| (v >> base) as u32;
    let (mut out, mut oe, mut pc, mut x) = (vec![], vec![], vec![], vec![]);
    let (mut rx, mut pulled, mut written, mut stimulus) = (vec![], vec![], vec![], vec![]);
    let mut fifo: VecDeque<u32> = VecDeque::new();
    let mut queue: VecDeque<(usize, u32)> = r.tx.iter().copied().collect();
    let mut last = None;
    for k in 0..r.cycles {
        let now = (r.outside)(k);
        if last != Some(now) {
            stimulus.push(format!("[{k},{},{}]", now.0, now.1));
            last = Some(now);
        }
        if let Some(&(from, word)) = queue.front() {
            if from <= k && !w.blocks[r.block].tx_full(r.sm) {
                w.blocks[r.block].txf_write(r.sm, word);
                fifo.push_back(word);
                written.push((k, word));
                queue.pop_front();
            }
        }
        let sm = &w.blocks[r.block].sm[r.sm];
        let pulls = matches!(
            Instruction::decode(words[usize::from(sm.pc())], r.program.program.side_set)
                .map(|i| i.operands),
            Some(InstructionOperands::PULL { .. })
        );
        w.step(&mut outside);
        let sm = &w.blocks[r.block].sm[r.sm];
        if pulls && !sm.stalled {
            let word = fifo
                .pop_front()
                .expect("a pull that did not stall took a word");
            pulled.push((k, word));
        }
        let (o, e) = w.driven();
        out.push(window(o));
        oe.push(window(e));
        pc.push(sm.pc());
        x.push(sm.x());
        while let Some(word) = w.pull(r.block, r.sm) {
            rx.push((k, word));
        }
    }
    assert!(queue.is_empty(), "{}: every TX word was written", r.name);
    let regs = &r.regs;
    let mut s = String::new();
    let _ = write!(
        s,
        "{{\"name\":\"{}\",\"block\":{},\"sm\":{},\"gpiobase\":{base},\
         \"words\":{},\"wrap_top\":{},\"wrap_bottom\":{},\"start\":{},\
         \"clkdiv\":{},\"execctrl\":{},\"shiftctrl\":{},\"pinctrl\":{},\
         \"x0\":{},\"out0\":{},\"oe0\":{},\"cycles\":{},\
         \"stimulus\":[{}],\"tx\":{},\
         \"out\":{},\"oe\":{},\"pc\":{},\"x\":{},\"rx\":{},\"pulled\":{}}}",
        r.name,
        r.block,
        r.sm,
        list(words),
        r.program.wrap_top,
        r.program.wrap_bottom,
        regs.start,
        regs.clkdiv,
        regs.execctrl,
        regs.shiftctrl,
        regs.pinctrl,
        r.x.unwrap_or(regs.x),
        window(initial.0),
        window(initial.1),
        r.cycles,
        stimulus.join(","),
        pairs(&written),
        list(out),
        list(oe),
        list(pc),
        list(x),
        pairs(&rx),
        pairs(&pulled),
    );
    s
}

/// Cycles at which a pin toggles: from `first`, at these gaps, repeated.
fn toggles(first: usize, gaps: &[usize], until: usize) -> Vec<usize> {
    let mut at = vec![first];
    for g in gaps.iter().cycle() {
        let next = at[at.len() - 1] + g;
        if next >= until {
            break;
        }
        at.push(next);
    }
    at
}

fn level(toggles: &[usize], k: usize, initial: bool) -> bool {
    initial ^ (toggles.iter().take_while(|&&t| t <= k).count() % 2 == 1)
}

fn main() {
    let path = std::env::args().nth(1);

    // The bus player: steps with and without a sample, D0-D7 driven or
    // not, counts 0 to 9, then two real cycles at 125 MHz; a pause with
    // the FIFO empty (the machine stalls at `pull`) before the second
    // batch. The outside drives D0-D7 with a value that changes every
    // third cycle, so a sample one cycle early or late reads another byte.
    let player = programs::bus_player();
    let idle = bus_cycle::IDLE;
    let mut tx: Vec<(usize, u32)> = [
        bus_cycle::step(0xFF, idle | 0xA5, false, 3),
        bus_cycle::step(0x00, idle & !(1 << bus_cycle::pin::RD), true, 0),
        bus_cycle::step(0x00, idle, true, 5),
        bus_cycle::step(0xFF, 0x3C | 1 << bus_cycle::pin::A0, true, 2),
        bus_cycle::step(0x0F, idle | 0x81, false, 0),
        bus_cycle::step(0xFF, idle, false, 9),
    ]
    .into_iter()
    .map(|w| (0, w))
    .collect();
    let fast = BusTiming {
        setup_ns: 16,
        strobe_ns: 90,
        hold_ns: 16,
        recovery_ns: 24,
    };
    for c in [
        Cycle::Write {
            a0: true,
            byte: 0x5A,
        },
        Cycle::Read { a0: false },
    ] {
        let steps = fast.steps(c, 125_000_000).expect("fits");
        tx.extend(steps.words().iter().map(|w| (150, *w)));
    }
    let bus_outside = |k: usize| (((k / 3) * 37 + 11) as u32 & 0xFF, 0xFF);
    let all = (1u32 << bus_cycle::pin::COUNT) - 1;
    let bus_run = Run {
        name: "bus_player",
        block: block::BUS,
        sm: 0,
        program: &player,
        regs: pioregs::bus_player(&player),
        x: None,
        pins: Some((idle, all)),
        cycles: 420,
        outside: &bus_outside,
        tx,
    };

    // The edge counters: X starts 60 above zero and wraps to all ones
    // about 120 cycles in; edges 1 to 9 cycles apart, and long gaps.
    let n = 2_000;
    let gaps = [
        1, 1, 2, 3, 1, 3, 2, 5, 1, 7, 4, 50, 1, 2, 300, 4, 1, 1, 1, 9, 6, 600, 2, 3,
    ];
    let at = |pin: u32| pioregs::in_window(pin, block::GPIOBASE[block::POUT]).expect("window");
    let rising = programs::edge_counter(true);
    let pout = toggles(20, &gaps, n);
    let dir = toggles(5, &[7, 3, 11, 1, 2], n);
    let pout_outside = |k: usize| {
        let l = u32::from(level(&pout, k, false)) << at(ppmc_bridge_fw::pins::POUT)
            | u32::from(level(&dir, k, false)) << at(ppmc_bridge_fw::pins::DIR);
        (l, u32::MAX)
    };
    let pout_run = Run {
        name: "pout_counter",
        block: block::POUT,
        sm: 0,
        program: &rising,
        regs: pioregs::pout_counter(&rising, false),
        x: Some(60),
        pins: None,
        cycles: n,
        outside: &pout_outside,
        tx: vec![],
    };

    // INT*, HOLD, AUX* on PIO2's SM0-2, each its own pattern; AUX* starts
    // high (its machine starts in the loop for a high pin).
    let both = programs::edge_counter(false);
    let initial = [false, false, true];
    let regs = pioregs::pin_counters(&both, initial);
    let patterns = [
        toggles(30, &gaps, n),
        toggles(11, &[3, 1, 2, 1, 1, 40, 2, 2, 1, 500, 3], n),
        toggles(90, &[2, 1, 1, 3, 250, 1, 4, 1, 2], n),
    ];
    let gpio = [
        ppmc_bridge_fw::pins::INT,
        ppmc_bridge_fw::pins::HOLD,
        ppmc_bridge_fw::pins::AUX,
    ];
    let pins_outside = |k: usize| {
        let l = (0..3).fold(0u32, |l, i| {
            l | u32::from(level(&patterns[i], k, initial[i])) << at(gpio[i])
        });
        (l, u32::MAX)
    };
    let names = ["int_counter", "hold_counter", "aux_counter"];
    let pin_runs = (0..3).map(|i| Run {
        name: names[i],
        block: block::PINS,
        sm: i,
        program: &both,
        regs: regs[i],
        x: Some(40 + i as u32),
        pins: None,
        cycles: n,
        outside: &pins_outside,
        tx: vec![],
    });

    // The self-test generator at address 0 (the image relocates it after
    // the bus player; `programs` tests the relocation): two bursts, the
    // second written while the first plays, so the machine goes straight
    // on; then a third after it waited at `pull`.
    let gen = programs::test_gen();
    let burst = |count, high, low| programs::test_gen_words(count, high, low).expect("makeable");
    let mut gen_tx: Vec<(usize, u32)> = burst(4, 5, 7).iter().map(|w| (0, *w)).collect();
    gen_tx.extend(burst(3, 3, 4).iter().map(|w| (10, *w)));
    gen_tx.extend(burst(2, 9, 6).iter().map(|w| (200, *w)));
    let tg = 1u32 << ppmc_bridge_fw::pins::TEST_GEN;
    let quiet = |_: usize| (0, 0);
    let gen_run = Run {
        name: "test_gen",
        block: block::BUS,
        sm: pioregs::TEST_GEN_SM,
        program: &gen,
        regs: pioregs::test_gen(&gen),
        x: None,
        pins: Some((0, tg)),
        cycles: 300,
        outside: &quiet,
        tx: gen_tx,
    };

    let traces: Vec<String> = [bus_run, pout_run, gen_run]
        .into_iter()
        .chain(pin_runs)
        .map(|r| trace(&r))
        .collect();
    let json = format!(
        "{{\"format\":1,\"warmup\":{WARMUP},\"traces\":[\n{}\n]}}\n",
        traces.join(",\n")
    );
    match path {
        Some(p) => std::fs::write(&p, json).unwrap_or_else(|e| panic!("{p}: {e}")),
        None => print!("{json}"),
    }
}
