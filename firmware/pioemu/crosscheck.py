#!/usr/bin/env python3
"""A second opinion on the bridge's PIO programs: pioemu against our model.

Reads the JSON that `firmware/bridge/examples/pio_trace.rs` writes (each
program as the firmware assembles and configures it, run on our PIO model
in `firmware/bridge/src/twin/pio/` over a fixed stimulus), runs the same
instruction words in pioemu (PyPI `rp2040-pio-emulator`, an independent
emulator written from the RP2040 datasheet) with the same configuration,
inputs and TX FIFO writes, and compares them cycle for cycle: PC, X, pin
directions, driven pin levels, the words pushed to the RX FIFO and the
words pulled from the TX FIFO. It stops at the first disagreement, names
the program, cycle, field and both values, and exits 1.

Usage (firmware/README.md, "A second opinion: pioemu"):

    firmware/pioemu/run                      # builds the trace, then this
    crosscheck.py TRACE.json [--perturb]

`--perturb` checks the check: it gives pioemu each program with one bit
changed (the target of its first `jmp`, one address off), and passes only
if every program then disagrees with our model.

Where the two emulators are built differently, this script makes pioemu
see what the RP2350 does, each time citing the RP2350 datasheet (chapter
11, PIO), and never the other way round:

1. Input synchroniser. Our model passes every GPIO input through the
   2-flip-flop synchroniser of 11.5.6.3 ("adds two cycles of latency to
   input sampling"); pioemu reads its input_source with no delay. The
   outside's levels reach pioemu two cycles late: on cycle k it reads what
   the outside drove on cycle k - 2.
2. IN pin mapping. pioemu has no IN_BASE (its README: "all pin numbers are
   with respect to GPIO 0"); on the RP2350 "the IN bus is a right-rotate
   of the GPIO input values, by PINCTRL_IN_BASE" (11.5.6.2). This script
   rotates the whole window by IN_BASE for pioemu, and every other pin
   field (the OUT, SET and side-set bases, the JMP pin) with it, and
   rotates pioemu's pins back to compare.
3. The output level register. The RP2350's PIO has "a 32-bit register for
   the output levels of each GPIO it can drive, and another register for
   the output enables" (11.5.6); pioemu keeps one word, pin_values, for
   levels read and levels written, and overwrites the levels of its input
   pins with the inputs each cycle. So a pin it turns to an output shows
   the last level read until the program writes one. This script keeps the
   output level register for pioemu: every level pioemu writes to its pins
   goes into it, and the levels compared are that register where the pin
   is an output.
4. MOV PINDIRS, an RP2350 addition (11.1.1: "Adds PINDIRS as a destination
   for MOV"; 11.4.10.2: destination 011, "uses same pin mapping as OUT").
   pioemu models the RP2040, where 011 is reserved; this script gives
   pioemu's decoder that destination, through pioemu's own OUT-mapping
   pindirs write. (No program uses it today.)
5. Side-set to pin directions. pioemu's side-set always writes pin levels;
   with EXECCTRL.SIDE_PINDIR set, the RP2350's writes directions (11.5.1,
   11.7 SMx_EXECCTRL: "side-set data is asserted to pin directions,
   instead of pin values"). This script makes pioemu's side-set write the
   directions when SIDE_PINDIR is set. pioemu applies a side-set after
   the instruction's own writes, also when it stalls, as the datasheet
   has it (11.5.6: "the side-set takes precedence"; 11.5.1: "If an
   instruction stalls, the side-set still takes effect immediately"); that
   part is its own.

Pins are numbered within the block's GPIOBASE window (bit i is GPIO
GPIOBASE + i): pioemu knows 32 pins, and the RP2350's PIO sees 32 GPIOs
from GPIOBASE (11.1.1). A pin that nothing drives reads 0 in pioemu; no
program here reads one. The RX FIFO is read every cycle in both, so its
depth (8 words when joined, 11.1: "4 x 32-bit bus FIFO in each direction
(TX/RX), reconfigurable as 8 x 32 in a single direction"; pioemu has 4)
never matters.
"""

import argparse
import json
import sys
from collections import deque
from dataclasses import replace
from functools import partial

import pioemu
import pioemu.emulation
import pioemu.instruction_decoder
import pioemu.primitive_operations as prim
from pioemu import State, clock_cycles_reached, emulate
from pioemu.bit_operations import update_bits_32

MASK32 = 0xFFFF_FFFF
# 11.5.6.3: the input synchroniser's latency, in cycles.
SYNC_CYCLES = 2


def field(value, lsb, bits):
    return value >> lsb & ((1 << bits) - 1)


def decode(t):
    """The register fields that matter, from the raw values, at the
    RP2350 datasheet's positions (11.7, SMx_CLKDIV, SMx_EXECCTRL,
    SMx_SHIFTCTRL, SMx_PINCTRL), read here independently of pioregs.rs."""
    c, e, s, p = t["clkdiv"], t["execctrl"], t["shiftctrl"], t["pinctrl"]
    return {
        "clkdiv_int": field(c, 16, 16),
        "clkdiv_frac": field(c, 8, 8),
        "side_en": field(e, 30, 1),
        "side_pindir": field(e, 29, 1),
        "jmp_pin": field(e, 24, 5),
        "inline_out_en": field(e, 18, 1),
        "out_sticky": field(e, 17, 1),
        "wrap_top": field(e, 12, 5),
        "wrap_bottom": field(e, 7, 5),
        "fjoin_rx": field(s, 31, 1),
        "fjoin_tx": field(s, 30, 1),
        "pull_thresh": field(s, 25, 5) or 32,
        "push_thresh": field(s, 20, 5) or 32,
        "out_shift_right": field(s, 19, 1),
        "in_shift_right": field(s, 18, 1),
        "autopull": field(s, 17, 1),
        "autopush": field(s, 16, 1),
        "fjoin_rx_put": field(s, 15, 1),
        "fjoin_rx_get": field(s, 14, 1),
        "in_count": field(s, 0, 5) or 32,
        "sideset_count": field(p, 29, 3),
        "set_count": field(p, 26, 3),
        "out_count": field(p, 20, 6),
        "in_base": field(p, 15, 5),
        "sideset_base": field(p, 10, 5),
        "set_base": field(p, 5, 5),
        "out_base": field(p, 0, 5),
    }


class Disagreement(Exception):
    pass


def rotr(v, r):
    return ((v >> r) | (v << (32 - r))) & MASK32 if r else v


def rotl(v, r):
    return ((v << r) | (v >> (32 - r))) & MASK32 if r else v


# pioemu's decoder binds its pin writers when it is made, inside emulate():
# the output level register (3.) and MOV PINDIRS (4.) go in before that.
_latch = {"value": 0}
_write_to_pins = prim.write_to_pins


def _write_to_pins_latched(base, count, supplier, state):
    new = _write_to_pins(base, count, supplier, state)
    mask = (((1 << count) - 1) << base) & MASK32
    _latch["value"] = (_latch["value"] & ~mask | new.pin_values & mask) & MASK32
    return new


class _Rp2350Decoder(pioemu.instruction_decoder.InstructionDecoder):
    def __init__(self, *args):
        super().__init__(*args)
        self.mov_destinations[3] = partial(
            prim.write_to_pin_directions, self.out_base, self.out_count
        )


_side_pindir = {"on": False}
_apply_side_set = pioemu.emulation._apply_side_set_to_pin_values


def _apply_side_set_to_pins_or_dirs(state, base, count, value):
    if _side_pindir["on"]:
        return replace(
            state,
            pin_directions=update_bits_32(state.pin_directions, value, base, count),
        )
    new = _apply_side_set(state, base, count, value)
    mask = (((1 << count) - 1) << base) & MASK32
    _latch["value"] = (_latch["value"] & ~mask | new.pin_values & mask) & MASK32
    return new


pioemu.instruction_decoder.write_to_pins = _write_to_pins_latched
pioemu.emulation.InstructionDecoder = _Rp2350Decoder
pioemu.emulation._apply_side_set_to_pin_values = _apply_side_set_to_pins_or_dirs


def config(t, cfg):
    """pioemu's keyword arguments for trace `t`, and the rotation (2.)."""
    refuse = [
        (cfg["clkdiv_int"] != 1 or cfg["clkdiv_frac"] != 0, "a clock divider other than 1"),
        (cfg["side_en"], "an optional side-set (SIDE_EN)"),
        (cfg["out_sticky"] or cfg["inline_out_en"], "OUT_STICKY or INLINE_OUT_EN"),
        (cfg["autopull"] or cfg["autopush"], "autopull or autopush"),
        (cfg["fjoin_rx_put"] or cfg["fjoin_rx_get"], "RX FIFO registers"),
        (cfg["wrap_top"] == 0, "wrap top 0 (pioemu reads 0 as 'the last word')"),
        (
            (cfg["wrap_top"], cfg["wrap_bottom"]) != (t["wrap_top"], t["wrap_bottom"]),
            "EXECCTRL's wrap differs from the program's",
        ),
    ]
    for bad, what in refuse:
        if bad:
            raise SystemExit(f"{t['name']}: {what}: not compared (this script does not model it)")
    r = cfg["in_base"]
    out_base = (cfg["out_base"] - r) % 32
    set_base = (cfg["set_base"] - r) % 32
    side_base = (cfg["sideset_base"] - r) % 32
    for what, b, n in [
        ("OUT", out_base, cfg["out_count"]),
        ("SET", set_base, cfg["set_count"]),
        ("side-set", side_base, cfg["sideset_count"]),
    ]:
        if n and b + n > 32:
            raise SystemExit(f"{t['name']}: {what} pins wrap after GPIO 31; pioemu does not wrap")
    kwargs = dict(
        shift_isr_right=bool(cfg["in_shift_right"]),
        shift_osr_right=bool(cfg["out_shift_right"]),
        pull_threshold=cfg["pull_thresh"],
        push_threshold=cfg["push_thresh"],
        out_base=out_base,
        out_count=cfg["out_count"],
        set_base=set_base,
        set_count=cfg["set_count"],
        side_set_base=side_base,
        side_set_count=cfg["sideset_count"],
        jmp_pin=(cfg["jmp_pin"] - r) % 32,
        wrap_target=cfg["wrap_bottom"],
        wrap_top=cfg["wrap_top"],
    )
    return kwargs, r


def levels(t):
    """What the outside drives on each cycle (window), from the change list."""
    n = t["cycles"]
    level = [0] * n
    changes = t["stimulus"]
    assert changes and changes[0][0] == 0, "the stimulus starts at cycle 0"
    for i, (k, lv, dr) in enumerate(changes):
        end = changes[i + 1][0] if i + 1 < len(changes) else n
        for c in range(k, end):
            level[c] = lv & dr
    return level


def perturbed(words):
    """`words` with the first `jmp` sent one address off (its target's
    lowest bit flipped), and what changed."""
    for i, w in enumerate(words):
        if w >> 13 == 0 and (w ^ 1) & 0x1F < len(words):
            changed = list(words)
            changed[i] = w ^ 1
            return changed, f"word {i}: {w:#06x} -> {w ^ 1:#06x}"
    raise SystemExit("no jmp to perturb")


def check(t, perturb):
    cfg = decode(t)
    kwargs, r = config(t, cfg)
    n = t["cycles"]
    words = list(t["words"])
    if perturb:
        words, _ = perturbed(words)
    # Unused instruction memory, as our model holds it: zeros.
    opcodes = words + [0] * (32 - len(words))
    outside = levels(t)

    # (1.) The synchroniser: cycle k reads the outside of cycle k - 2; the
    # outside drove its first levels since before cycle 0.
    def input_source(clock: int) -> int:
        return rotr(outside[max(clock - SYNC_CYCLES, 0)], r)

    tx = {}
    for k, w in t["tx"]:
        tx.setdefault(k, []).append(w)
    # 11.1: 4 words each way, 8 in one direction when joined.
    tx_depth = 8 if cfg["fjoin_tx"] else (0 if cfg["fjoin_rx"] else 4)
    rx = {}
    for k, w in t["rx"]:
        rx.setdefault(k, []).append(w)
    pulled = {k: w for k, w in t["pulled"]}

    _latch["value"] = rotr(t["out0"], r)
    _side_pindir["on"] = bool(cfg["side_pindir"])
    state = State(
        program_counter=t["start"],
        x_register=t["x0"],
        pin_values=rotr(t["out0"] & t["oe0"], r),
        pin_directions=rotr(t["oe0"], r),
        transmit_fifo=deque(tx.get(0, [])),
    )

    def differ(k, what, ours, theirs):
        raise Disagreement(
            f"{t['name']}: cycle {k}: {what}: our model {ours}, pioemu {theirs}"
        )

    k = 0
    for before, after in emulate(
        opcodes,
        stop_when=clock_cycles_reached(n),
        initial_state=state,
        input_source=input_source,
        **kwargs,
    ):
        assert after.clock == k + 1, "one cycle a step: no delays in these programs"
        dirs = rotl(after.pin_directions, r)
        out = rotl(_latch["value"], r) & dirs
        ours_out = t["out"][k] & t["oe"][k]
        if after.program_counter != t["pc"][k]:
            differ(k, "PC", t["pc"][k], after.program_counter)
        if after.x_register != t["x"][k]:
            differ(k, "X", hex(t["x"][k]), hex(after.x_register))
        if dirs != t["oe"][k]:
            differ(k, "pin directions", hex(t["oe"][k]), hex(dirs))
        if out != ours_out:
            differ(k, "driven pin levels", hex(ours_out), hex(out))
        took = None
        if len(after.transmit_fifo) < len(before.transmit_fifo):
            took = before.transmit_fifo[0]
        if took != pulled.get(k):
            differ(k, "word pulled from the TX FIFO", pulled.get(k), took)
        pushed = list(after.receive_fifo)
        after.receive_fifo.clear()
        if pushed != rx.get(k, []):
            differ(k, "words pushed to the RX FIFO", rx.get(k, []), pushed)
        # The CPU's writes before the next cycle, into a FIFO with room.
        for w in tx.get(k + 1, []):
            if len(after.transmit_fifo) >= tx_depth:
                differ(k + 1, "a TX FIFO write", "had room", "found it full")
            after.transmit_fifo.append(w)
        k += 1
    if k != n:
        differ(k, "running", "ran on", f"stopped (pioemu could not decode {opcodes[after.program_counter]:#06x})")
    return {
        "cycles": n,
        "pushed": len(t["rx"]),
        "pulled": len(t["pulled"]),
        "changes": len(t["stimulus"]) - 1,
    }


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("trace", help="JSON from `cargo run --example pio_trace`")
    ap.add_argument(
        "--perturb",
        action="store_true",
        help="give pioemu each program with one bit changed; pass only if each then disagrees",
    )
    args = ap.parse_args()
    with open(args.trace) as f:
        doc = json.load(f)
    assert doc.get("format") == 1, "trace format 1"
    print(f"pioemu {pioemu.__version__} against our PIO model (firmware/bridge/src/twin/pio/)")
    if args.perturb:
        missed = []
        for t in doc["traces"]:
            _, what = perturbed(t["words"])
            try:
                check(t, True)
                missed.append(t["name"])
                print(f"  {t['name']} perturbed ({what}): NOT caught")
            except Disagreement as d:
                print(f"  {t['name']} perturbed ({what}): caught: {d}")
        if missed:
            print(f"crosscheck --perturb: a changed program passed: {', '.join(missed)}")
            return 1
        print(f"crosscheck --perturb: a one-bit change caught in each of {len(doc['traces'])} programs")
        return 0
    total = 0
    for t in doc["traces"]:
        try:
            s = check(t, args.perturb)
        except Disagreement as d:
            print(f"DISAGREE {d}")
            return 1
        total += s["cycles"]
        print(
            f"  {t['name']}: {s['cycles']} cycles agree: {s['changes']} input changes, "
            f"{s['pulled']} words pulled, {s['pushed']} pushed"
        )
    print(f"crosscheck: {len(doc['traces'])} programs, {total} cycles, no disagreement")
    return 0


if __name__ == "__main__":
    sys.exit(main())
