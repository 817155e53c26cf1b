#!/usr/bin/env bash
# Stop switching's chopping period (Section 3-5-1, Diagram 3-5: 65 us on,
# 108.75 us off at 16 MHz), measured from the stamps of the console's pin
# samples (docs/console.md, "Measuring through a bridge"):
#
#   docs/examples/chop-period.sh                                  # the emulator
#   docs/examples/chop-period.sh --target serial:/dev/ttyACM0     # a board
#
# Arguments go to `ppmc console`; PPMC names the tool (default: ppmc on
# PATH). It prints each stretch of the phases on or off between two
# changes the samples saw, from the stamps: where the target read the pins.
set -euo pipefail
ppmc=${PPMC:-ppmc}
{
    # Initialize a 4-phase motor with stop switching (bit 5), and wait out
    # the initialization processing (Table 3-3: at most 162.8 ms).
    echo 'wc 0x22; wd 100; wd 20; wd 100; wd 0; await ibf=0; wait 170ms'
    # 600 us of samples, 250 ns apart.
    for _ in $(seq 2400); do echo 'pins; wait 250ns'; done
} | "$ppmc" console "$@" | awk '$1 == "pins" {
    on = ($6 != "s=0b00000"); t = $9; sub("us", "", t)
    if (seen && on != was) {
        if (last != "") printf "%s %.3fus\n", (was ? "on" : "off"), t - last
        last = t
    }
    was = on; seen = 1
}'
