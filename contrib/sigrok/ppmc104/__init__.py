##
## ppmc104: the host bus of the PPMC-104BFP stepper-motor pulse controller,
## for PulseView and sigrok-cli (libsigrokdecode).
##
## SPDX-License-Identifier: MIT OR Apache-2.0
##

'''
The PPMC-104BFP's 8-bit host bus: CS#, RD#, WR# (active low), A0 and
D0-D7, decoded into register accesses by the datasheet's Table 3-1:

  CS# A0 RD# WR#
   L  L   L   H   read  data register
   L  H   L   H   read  status register
   L  L   H   L   write data register
   L  H   H   L   write command register

A strobe is CS# and RD# (or WR#) low together; it ends when either goes
high, and the byte is what D0-D7 held in its last sample (as a latch at the
strobe's rising edge takes it). `ppmc export --bus` writes captures with
these channel names; ppmc's own decoder (`ppmc decode`) reads the same
bus the same way.
'''

from .pd import Decoder
