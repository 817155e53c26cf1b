//! A USB host for one CDC ACM device, as Linux's `cdc_acm` drives the
//! bridge: it enumerates the device (USB 2.0 chapter 9: reset, the
//! device descriptor, SET_ADDRESS, the configuration, SET_CONFIGURATION),
//! opens the port as a terminal does (CDC PSTN 6.3: SET_LINE_CODING,
//! SET_CONTROL_LINE_STATE with DTR and RTS), then moves bytes through the
//! data interface's bulk endpoints.
//!
//! It speaks in transactions ([`Transactions`]), one at a time, and lets
//! the device's firmware run between them ([`Transactions::run`]), as a
//! host controller schedules them in frames. A device that NAKs is asked
//! again after a while; every wait is bounded in the device's cycles.

/// A transaction's answer from the device to an IN token.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum InReply {
    /// A data packet, and whether its PID was DATA1.
    Data(Vec<u8>, bool),
    Nak,
    Stall,
}

/// A transaction's answer to an OUT token and its data.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum OutReply {
    Ack,
    Nak,
    Stall,
}

/// What a host controller does on the bus, and the device's time.
pub trait Transactions {
    /// Whether the device pulls D+ up (it is ready to be seen).
    fn connected(&mut self) -> bool;
    /// A bus reset: the device's address goes back to 0.
    fn bus_reset(&mut self);
    /// A SETUP transaction to endpoint 0 of `addr` (always DATA0).
    fn setup(&mut self, addr: u8, packet: [u8; 8]) -> OutReply;
    /// An IN transaction.
    fn in_token(&mut self, addr: u8, ep: u8) -> InReply;
    /// An OUT transaction with `data`, DATA1 when `data1`.
    fn out_token(&mut self, addr: u8, ep: u8, data: &[u8], data1: bool) -> OutReply;
    /// Lets the device run `cycles` of its clock.
    fn run(&mut self, cycles: u64) -> Result<(), String>;
}

/// The address the host gives the device.
const ADDRESS: u8 = 1;
/// Endpoint 0's packet size the host assumes until the descriptor says
/// (8 bytes is the least a full-speed device may have: USB 2.0 5.5.3).
const EP0_FIRST: usize = 8;
/// Cycles between two tries of a NAKed transaction: 10 us at 150 MHz.
pub const RETRY_CYCLES: u64 = 1_500;
/// Tries of one transaction before the host gives up: 2 s of the device's
/// time at [`RETRY_CYCLES`] each.
const TRIES: u32 = 200_000;

/// The device once enumerated: where its bulk endpoints are.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Port {
    pub bulk_in: u8,
    pub bulk_out: u8,
    /// The bulk endpoints' packet size.
    pub packet: usize,
    /// The data toggles of the bulk endpoints: the next PID is DATA1.
    toggle_in: bool,
    toggle_out: bool,
    /// Descriptor strings the host read, for the log.
    pub product: String,
    pub serial: String,
}

fn setup_packet(request_type: u8, request: u8, value: u16, index: u16, length: u16) -> [u8; 8] {
    let mut p = [0u8; 8];
    p[0] = request_type;
    p[1] = request;
    p[2..4].copy_from_slice(&value.to_le_bytes());
    p[4..6].copy_from_slice(&index.to_le_bytes());
    p[6..8].copy_from_slice(&length.to_le_bytes());
    p
}

/// Asks again while the device NAKs, running it between tries.
fn patiently<T: Transactions, R>(
    t: &mut T,
    what: &str,
    mut once: impl FnMut(&mut T) -> Option<R>,
) -> Result<R, String> {
    for _ in 0..TRIES {
        if let Some(r) = once(t) {
            return Ok(r);
        }
        t.run(RETRY_CYCLES)?;
    }
    Err(format!(
        "{what}: the device NAKed for {} ms of its time",
        u64::from(TRIES) * RETRY_CYCLES / 150_000
    ))
}

/// A control transfer with an IN data stage (USB 2.0 8.5.3): the bytes
/// the device sent, at most `length`.
fn control_in<T: Transactions>(
    t: &mut T,
    addr: u8,
    max_packet: usize,
    setup: [u8; 8],
) -> Result<Vec<u8>, String> {
    let length = usize::from(u16::from_le_bytes([setup[6], setup[7]]));
    let what = format!("the control request {:02x} {:02x}", setup[0], setup[1]);
    patiently(t, &what, |t| match t.setup(addr, setup) {
        OutReply::Ack => Some(()),
        _ => None,
    })?;
    let mut data = Vec::new();
    let mut data1 = true;
    loop {
        let packet = patiently(t, &what, |t| match t.in_token(addr, 0) {
            InReply::Data(d, pid1) => Some(Ok((d, pid1))),
            InReply::Nak => None,
            InReply::Stall => Some(Err(format!("{what}: the device stalled"))),
        })??;
        let (bytes, pid1) = packet;
        if pid1 != data1 {
            // A repeat of the last packet (its ACK was lost): USB 2.0 8.6.
            continue;
        }
        data1 = !data1;
        data.extend_from_slice(&bytes);
        if bytes.len() < max_packet || data.len() >= length {
            break;
        }
    }
    // The status stage: a zero-length OUT, DATA1.
    patiently(t, &what, |t| match t.out_token(addr, 0, &[], true) {
        OutReply::Ack => Some(Ok(())),
        OutReply::Nak => None,
        OutReply::Stall => Some(Err(format!("{what}: stalled in its status stage"))),
    })??;
    data.truncate(length);
    Ok(data)
}

/// A control transfer with no data stage or an OUT one (USB 2.0 8.5.3).
fn control_out<T: Transactions>(
    t: &mut T,
    addr: u8,
    max_packet: usize,
    setup: [u8; 8],
    data: &[u8],
) -> Result<(), String> {
    let what = format!("the control request {:02x} {:02x}", setup[0], setup[1]);
    patiently(t, &what, |t| match t.setup(addr, setup) {
        OutReply::Ack => Some(()),
        _ => None,
    })?;
    let mut data1 = true;
    for chunk in data.chunks(max_packet.max(1)) {
        patiently(t, &what, |t| match t.out_token(addr, 0, chunk, data1) {
            OutReply::Ack => Some(Ok(())),
            OutReply::Nak => None,
            OutReply::Stall => Some(Err(format!("{what}: the device stalled"))),
        })??;
        data1 = !data1;
    }
    // The status stage: a zero-length IN, DATA1.
    patiently(t, &what, |t| match t.in_token(addr, 0) {
        InReply::Data(d, _) if d.is_empty() => Some(Ok(())),
        InReply::Data(d, _) => Some(Err(format!(
            "{what}: {} bytes in the status stage",
            d.len()
        ))),
        InReply::Nak => None,
        InReply::Stall => Some(Err(format!("{what}: stalled in its status stage"))),
    })?
}

/// A string descriptor's text (USB 2.0 9.6.7), or "" if it has none.
fn string<T: Transactions>(t: &mut T, max_packet: usize, index: u8) -> Result<String, String> {
    if index == 0 {
        return Ok(String::new());
    }
    let d = control_in(
        t,
        ADDRESS,
        max_packet,
        setup_packet(0x80, 6, 0x0300 | u16::from(index), 0x0409, 255),
    )?;
    let units: Vec<u16> = d
        .get(2..)
        .unwrap_or(&[])
        .chunks_exact(2)
        .map(|c| u16::from_le_bytes([c[0], c[1]]))
        .collect();
    Ok(String::from_utf16_lossy(&units))
}

/// The bulk endpoints of the configuration's CDC data interface (class
/// 0x0A): (IN address, OUT address, packet size).
fn data_endpoints(config: &[u8]) -> Result<(u8, u8, usize), String> {
    let (mut in_ep, mut out_ep, mut size) = (None, None, 0);
    let mut in_data_interface = false;
    let mut at = 0;
    while at + 2 <= config.len() {
        let len = usize::from(config[at]);
        if len < 2 || at + len > config.len() {
            return Err(format!(
                "a descriptor at byte {at} of the configuration runs past it"
            ));
        }
        let d = &config[at..at + len];
        match d[1] {
            4 if len >= 9 => in_data_interface = d[5] == 0x0A,
            5 if len >= 7 && in_data_interface && d[3] & 3 == 2 => {
                size = usize::from(u16::from_le_bytes([d[4], d[5]]));
                if d[2] & 0x80 != 0 {
                    in_ep = Some(d[2] & 0x0F);
                } else {
                    out_ep = Some(d[2] & 0x0F);
                }
            }
            _ => {}
        }
        at += len;
    }
    match (in_ep, out_ep) {
        (Some(i), Some(o)) if size > 0 => Ok((i, o, size)),
        _ => Err("the configuration has no CDC data interface with two bulk endpoints".into()),
    }
}

/// Enumerates the device and opens its port: what happens between a
/// device's plugging in and a terminal program's first byte.
pub fn enumerate<T: Transactions>(t: &mut T) -> Result<Port, String> {
    patiently(t, "waiting for the device to connect", |t| {
        t.connected().then_some(())
    })?;
    t.bus_reset();
    t.run(150_000)?; // 1 ms: USB 2.0 7.1.7.5 gives a device 10 ms.
    let first = control_in(
        t,
        0,
        EP0_FIRST,
        setup_packet(0x80, 6, 0x0100, 0, EP0_FIRST as u16),
    )?;
    let max_packet = usize::from(*first.get(7).ok_or("a device descriptor under 8 bytes")?);
    t.bus_reset();
    t.run(150_000)?;
    control_out(
        t,
        0,
        max_packet,
        setup_packet(0x00, 5, u16::from(ADDRESS), 0, 0),
        &[],
    )?;
    t.run(300_000)?; // 2 ms for SET_ADDRESS (USB 2.0 9.2.6.3).
    let device = control_in(t, ADDRESS, max_packet, setup_packet(0x80, 6, 0x0100, 0, 18))?;
    if device.len() < 18 {
        return Err(format!("a device descriptor of {} bytes", device.len()));
    }
    let head = control_in(t, ADDRESS, max_packet, setup_packet(0x80, 6, 0x0200, 0, 9))?;
    let total = u16::from_le_bytes([
        *head
            .get(2)
            .ok_or("a configuration descriptor under 4 bytes")?,
        *head
            .get(3)
            .ok_or("a configuration descriptor under 4 bytes")?,
    ]);
    let config = control_in(
        t,
        ADDRESS,
        max_packet,
        setup_packet(0x80, 6, 0x0200, 0, total),
    )?;
    let (bulk_in, bulk_out, packet) = data_endpoints(&config)?;
    let product = string(t, max_packet, device[15])?;
    let serial = string(t, max_packet, device[16])?;
    control_out(
        t,
        ADDRESS,
        max_packet,
        setup_packet(0x00, 9, u16::from(config[5]), 0, 0),
        &[],
    )?;
    // SET_LINE_CODING: 115200 8N1 (the baud rate means nothing over USB).
    let coding = [0x00, 0xC2, 0x01, 0x00, 0, 0, 8];
    control_out(
        t,
        ADDRESS,
        max_packet,
        setup_packet(0x21, 0x20, 0, 0, 7),
        &coding,
    )?;
    // SET_CONTROL_LINE_STATE: DTR and RTS, as opening a tty sets them.
    control_out(
        t,
        ADDRESS,
        max_packet,
        setup_packet(0x21, 0x22, 3, 0, 0),
        &[],
    )?;
    Ok(Port {
        bulk_in,
        bulk_out,
        packet,
        toggle_in: false,
        toggle_out: false,
        product,
        serial,
    })
}

impl Port {
    /// Sends one packet of `data` (at most [`Port::packet`] bytes):
    /// `Ok(true)` when the device took it, `Ok(false)` when it NAKed.
    pub fn send<T: Transactions>(&mut self, t: &mut T, data: &[u8]) -> Result<bool, String> {
        match t.out_token(ADDRESS, self.bulk_out, data, self.toggle_out) {
            OutReply::Ack => {
                self.toggle_out = !self.toggle_out;
                Ok(true)
            }
            OutReply::Nak => Ok(false),
            OutReply::Stall => Err(format!("bulk OUT endpoint {} stalled", self.bulk_out)),
        }
    }

    /// Asks the device for one packet: its bytes, empty when it had none.
    pub fn receive<T: Transactions>(&mut self, t: &mut T) -> Result<Vec<u8>, String> {
        match t.in_token(ADDRESS, self.bulk_in) {
            InReply::Data(d, pid1) => {
                if pid1 != self.toggle_in {
                    // A packet sent again after a lost ACK: USB 2.0 8.6.4.
                    return Ok(Vec::new());
                }
                self.toggle_in = !self.toggle_in;
                Ok(d)
            }
            InReply::Nak => Ok(Vec::new()),
            InReply::Stall => Err(format!("bulk IN endpoint {} stalled", self.bulk_in)),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A CDC ACM configuration as embassy-usb writes it (USB CDC 1.2,
    /// PSTN 5.3): the communication interface with its notification
    /// endpoint, then the data interface with bulk OUT 0x01 and IN 0x82.
    fn cdc_configuration() -> Vec<u8> {
        let mut c = vec![9, 2, 0, 0, 2, 1, 0, 0x80, 50];
        c.extend([8, 0x0B, 0, 2, 2, 2, 0, 0]); // interface association
        c.extend([9, 4, 0, 0, 1, 2, 2, 0, 0]); // communication interface
        c.extend([5, 0x24, 0, 0x10, 0x01]); // CDC header
        c.extend([7, 5, 0x83, 3, 8, 0, 255]); // notification: interrupt IN
        c.extend([9, 4, 1, 0, 2, 0x0A, 0, 0, 0]); // data interface
        c.extend([7, 5, 0x01, 2, 64, 0, 0]); // bulk OUT 1
        c.extend([7, 5, 0x82, 2, 64, 0, 0]); // bulk IN 2
        let total = c.len() as u16;
        c[2..4].copy_from_slice(&total.to_le_bytes());
        c
    }

    #[test]
    fn the_data_interfaces_bulk_endpoints_are_found_not_the_notification() {
        assert_eq!(data_endpoints(&cdc_configuration()), Ok((2, 1, 64)));
    }

    #[test]
    fn a_configuration_without_a_data_interface_or_cut_short_is_refused() {
        let c = cdc_configuration();
        let without: Vec<u8> = c[..c.len() - 23].to_vec();
        assert!(data_endpoints(&without).is_err());
        let cut = &c[..c.len() - 3];
        let e = data_endpoints(cut).expect_err("cut short");
        assert!(e.contains("runs past it"), "{e}");
    }
}
