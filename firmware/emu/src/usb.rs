//! The USB host's side of the emulated RP2350: each transaction of
//! [`cdc`](crate::cdc) handed to rp2350-emu's USB controller
//! (`UsbHost`, vendored: PPMC-CHANGES.md), the image running between
//! them.

use crate::cdc::{InReply, OutReply, Transactions};
use crate::machine::Machine;
use rp2350_emu::{DataPid, Handshake, InResponse};

/// The host controller, wired to the machine's USB port.
#[derive(Debug)]
pub struct Host<'a> {
    m: &'a mut Machine,
}

impl<'a> Host<'a> {
    pub fn new(m: &'a mut Machine) -> Host<'a> {
        Host { m }
    }

    /// The machine's clock.
    pub fn cycles(&self) -> u64 {
        self.m.cycles()
    }
}

fn handshake(h: Handshake) -> OutReply {
    match h {
        Handshake::Ack => OutReply::Ack,
        Handshake::Stall => OutReply::Stall,
        // A device that does not answer (its address or endpoint not yet
        // set up) is asked again, as a host does after a timeout.
        Handshake::Nak | Handshake::NoResponse => OutReply::Nak,
    }
}

impl Transactions for Host<'_> {
    fn connected(&mut self) -> bool {
        self.m.emu.usb_host().attach()
    }

    fn bus_reset(&mut self) {
        self.m.emu.usb_host().bus_reset();
    }

    fn setup(&mut self, addr: u8, packet: [u8; 8]) -> OutReply {
        handshake(self.m.emu.usb_host().setup(addr, packet))
    }

    fn in_token(&mut self, addr: u8, ep: u8) -> InReply {
        match self.m.emu.usb_host().in_token(addr, ep) {
            InResponse::Data { data, pid } => InReply::Data(data, pid == DataPid::Data1),
            InResponse::Stall => InReply::Stall,
            InResponse::Nak | InResponse::NoResponse => InReply::Nak,
        }
    }

    fn out_token(&mut self, addr: u8, ep: u8, data: &[u8], data1: bool) -> OutReply {
        let pid = if data1 {
            DataPid::Data1
        } else {
            DataPid::Data0
        };
        handshake(self.m.emu.usb_host().out_token(addr, ep, data, pid))
    }

    fn run(&mut self, cycles: u64) -> Result<(), String> {
        self.m.run(cycles)
    }
}
