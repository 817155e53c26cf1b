##
## ppmc104: the host bus of the PPMC-104BFP (see __init__.py).
##
## SPDX-License-Identifier: MIT OR Apache-2.0
##

import sigrokdecode as srd

CS, RD, WR, A0 = 0, 1, 2, 3
D0 = 4

# Annotation classes, in this order.
WC, WD, RS, RDD, WARN = range(5)

class Decoder(srd.Decoder):
    api_version = 3
    id = 'ppmc104'
    name = 'PPMC-104BFP'
    longname = 'PPMC-104BFP host bus'
    desc = 'Register accesses of the PPMC-104BFP stepper-motor pulse controller.'
    license = 'mit'
    inputs = ['logic']
    outputs = []
    tags = ['Embedded/industrial']
    channels = (
        {'id': 'cs', 'name': 'CS#', 'desc': 'Chip select (active low)'},
        {'id': 'rd', 'name': 'RD#', 'desc': 'Read strobe (active low)'},
        {'id': 'wr', 'name': 'WR#', 'desc': 'Write strobe (active low)'},
        {'id': 'a0', 'name': 'A0', 'desc': 'Register select: H command/status, L data'},
    ) + tuple({'id': 'd%d' % i, 'name': 'D%d' % i, 'desc': 'Data line %d' % i}
              for i in range(8))
    annotations = (
        ('wc', 'Write command register'),
        ('wd', 'Write data register'),
        ('rs', 'Read status register'),
        ('rd', 'Read data register'),
        ('warning', 'Warning'),
    )
    annotation_rows = (
        ('accesses', 'Register accesses', (WC, WD, RS, RDD)),
        ('warnings', 'Warnings', (WARN,)),
    )

    def __init__(self):
        self.reset()

    def reset(self):
        pass

    def start(self):
        self.out_ann = self.register(srd.OUTPUT_ANN)

    def byte(self, pins):
        return sum((pins[D0 + i] & 1) << i for i in range(8))

    def decode(self):
        while True:
            # A strobe begins: RD# or WR# falls with CS# low, or CS# falls
            # with one of them low.
            pins = self.wait([{RD: 'f', CS: 'l'}, {WR: 'f', CS: 'l'},
                              {CS: 'f', RD: 'l'}, {CS: 'f', WR: 'l'}])
            if pins[RD] == 0 and pins[WR] == 0:
                self.put(self.samplenum, self.samplenum, self.out_ann,
                         [WARN, ['RD# and WR# low together', 'Bus fight']])
                continue
            write = pins[WR] == 0
            strobe = WR if write else RD
            ss = self.samplenum
            last = pins
            # Until it ends, the lines of its last sample.
            while True:
                pins = self.wait([{strobe: 'r'}, {CS: 'r'}] +
                                 [{D0 + i: 'e'} for i in range(8)] + [{A0: 'e'}])
                if pins[strobe] == 1 or pins[CS] == 1:
                    break
                last = pins
            value = self.byte(last)
            reg = last[A0] == 1
            if write:
                cls, words = (WC, ['Write command 0x%02X' % value, 'WC 0x%02X' % value, 'WC']) if reg \
                    else (WD, ['Write data 0x%02X' % value, 'WD 0x%02X' % value, 'WD'])
            else:
                cls, words = (RS, ['Read status 0x%02X' % value, 'RS 0x%02X' % value, 'RS']) if reg \
                    else (RDD, ['Read data 0x%02X' % value, 'RD 0x%02X' % value, 'RD'])
            self.put(ss, self.samplenum, self.out_ann, [cls, words])
