//! The bridge's schematic, `hardware/ppmc-bridge.kicad_sch`, against the pin
//! map in [`ppmc_bridge_fw::pins`], its parts list `hardware/bom.csv` and the
//! connector table of `docs/bridge-hardware.md`.
//!
//! KiCad is not needed: a small S-expression reader loads the schematic
//! (KiCad 6 format). The schematic joins every pin to its net by a net label
//! placed on the pin's connection point, with no wires; this test computes
//! each pin's point from the symbol's position, rotation and mirror, finds
//! the label there, and builds the netlist from the labels' names. Then it
//! checks that every GPIO of the pin map reaches, through the right buffer
//! channel, the right pin of the chip's header; that no net joins two
//! signals; the safe state while the bridge boots or is off; each IC's
//! supplies and decoupling; and that the parts list and the doc agree with
//! the schematic.

use ppmc_bridge_fw::pins;
use std::collections::{BTreeMap, BTreeSet};
use std::path::PathBuf;

// ---------------------------------------------------------------------------
// S-expressions
// ---------------------------------------------------------------------------

#[derive(Debug, Clone, PartialEq)]
enum Sx {
    /// A bare token: a keyword, a number, a UUID.
    Atom(String),
    /// A quoted string, unescaped.
    Str(String),
    List(Vec<Sx>),
}

fn parse_sx(text: &str) -> Result<Sx, String> {
    let mut stack: Vec<Vec<Sx>> = vec![Vec::new()];
    let mut chars = text.char_indices().peekable();
    while let Some((at, c)) = chars.next() {
        match c {
            '(' => stack.push(Vec::new()),
            ')' => {
                let list = stack.pop().ok_or(format!("unbalanced ')' at byte {at}"))?;
                stack
                    .last_mut()
                    .ok_or(format!("unbalanced ')' at byte {at}"))?
                    .push(Sx::List(list));
            }
            '"' => {
                let mut s = String::new();
                loop {
                    match chars.next() {
                        Some((_, '\\')) => match chars.next() {
                            Some((_, 'n')) => s.push('\n'),
                            Some((_, e)) => s.push(e),
                            None => return Err("a string ends in '\\'".into()),
                        },
                        Some((_, '"')) => break,
                        Some((_, ch)) => s.push(ch),
                        None => return Err(format!("a string at byte {at} is not closed")),
                    }
                }
                stack
                    .last_mut()
                    .ok_or("text outside the top list")?
                    .push(Sx::Str(s));
            }
            c if c.is_whitespace() => {}
            _ => {
                let mut s = String::from(c);
                while let Some(&(_, n)) = chars.peek() {
                    if n.is_whitespace() || n == '(' || n == ')' || n == '"' {
                        break;
                    }
                    s.push(n);
                    chars.next();
                }
                stack
                    .last_mut()
                    .ok_or("text outside the top list")?
                    .push(Sx::Atom(s));
            }
        }
    }
    let mut top = stack.pop().ok_or("no text")?;
    if !stack.is_empty() {
        return Err(format!("{} list(s) not closed", stack.len()));
    }
    if top.len() != 1 {
        return Err(format!("{} top-level items, not one", top.len()));
    }
    Ok(top.remove(0))
}

impl Sx {
    fn items(&self) -> &[Sx] {
        match self {
            Sx::List(v) => v,
            _ => &[],
        }
    }
    /// The text of item `i` (an atom or a string).
    fn text(&self, i: usize) -> Option<&str> {
        match self.items().get(i)? {
            Sx::Atom(s) | Sx::Str(s) => Some(s),
            Sx::List(_) => None,
        }
    }
    fn head(&self) -> Option<&str> {
        match self.items().first()? {
            Sx::Atom(s) => Some(s),
            _ => None,
        }
    }
    fn children<'a>(&'a self, key: &'a str) -> impl Iterator<Item = &'a Sx> + 'a {
        self.items().iter().filter(move |c| c.head() == Some(key))
    }
    fn child(&self, key: &str) -> Option<&Sx> {
        self.items().iter().find(|c| c.head() == Some(key))
    }
    fn num(&self, i: usize) -> Result<f64, String> {
        let t = self
            .text(i)
            .ok_or(format!("no number at {i} in {:?}", self.head()))?;
        t.parse()
            .map_err(|e| format!("{t:?} is not a number ({e}) in {:?}", self.head()))
    }
}

// ---------------------------------------------------------------------------
// The schematic's geometry
// ---------------------------------------------------------------------------

/// A point in KiCad's schematic internal units (100 nm), so that points
/// compare exactly.
type Point = (i64, i64);

fn iu(mm: f64) -> i64 {
    (mm * 10_000.0).round() as i64
}

/// Where a library pin's connection point lands on the sheet. KiCad's symbol
/// editor has Y up and the schematic has Y down, so the plain symbol
/// (angle 0) flips Y. KiCad 6 reads `(at X Y ANGLE)` into a matrix
/// `(x1, y1, x2, y2)`, sheet = (x1*px + y1*py, x2*px + y2*py): 0 -> (1, 0,
/// 0, -1), 90 -> (0, -1, -1, 0), 180 -> (-1, 0, 0, 1), 270 -> (0, 1, 1, 0)
/// (eeschema's s-expression parser). `(mirror x)` then negates the sheet Y
/// and `(mirror y)` the sheet X: KiCad composes the mirror after the
/// rotation (SCH_SYMBOL::SetOrientation), so a mirrored, rotated symbol is
/// rotated first and flipped on the sheet.
fn pin_on_sheet(pin: Point, at: Point, angle: i64, mirror: Option<&str>) -> Result<Point, String> {
    let (mut x1, mut y1, mut x2, mut y2) = match angle.rem_euclid(360) {
        0 => (1, 0, 0, -1),
        90 => (0, -1, -1, 0),
        180 => (-1, 0, 0, 1),
        270 => (0, 1, 1, 0),
        a => return Err(format!("angle {a}: KiCad takes 0, 90, 180 or 270")),
    };
    match mirror {
        None => {}
        Some("x") => {
            x2 = -x2;
            y2 = -y2;
        }
        Some("y") => {
            x1 = -x1;
            y1 = -y1;
        }
        Some(m) => return Err(format!("mirror {m:?}: KiCad takes x or y")),
    }
    let (px, py) = pin;
    Ok((at.0 + x1 * px + y1 * py, at.1 + x2 * px + y2 * py))
}

#[derive(Debug, Clone)]
struct LibPin {
    number: String,
    name: String,
    at: Point,
    /// 0: every unit.
    unit: i64,
    /// 0: both body styles.
    style: i64,
}

#[derive(Debug, Clone)]
struct Placed {
    reference: String,
    lib_id: String,
    value: String,
    /// (number, name, point on the sheet)
    pins: Vec<(String, String, Point)>,
}

impl Placed {
    /// The library symbol's name without its library: "74AHCT244".
    fn part(&self) -> &str {
        self.lib_id.rsplit(':').next().unwrap_or(&self.lib_id)
    }
}

#[derive(Debug)]
struct Schematic {
    symbols: Vec<Placed>,
    labels: Vec<(String, Point)>,
    no_connects: Vec<Point>,
    /// What KiCad 6's `symbol_instances` says each symbol is called.
    instance_refs: BTreeSet<String>,
}

fn read_schematic(text: &str) -> Result<Schematic, String> {
    let top = parse_sx(text)?;
    if top.head() != Some("kicad_sch") {
        return Err("not a kicad_sch file".into());
    }
    for wiring in ["wire", "junction", "bus", "bus_entry", "sheet"] {
        if top.child(wiring).is_some() {
            return Err(format!(
                "the schematic has a `{wiring}`: this test reads nets from labels on pins only \
                 (hardware/README.md); join pins by labels"
            ));
        }
    }
    let mut lib: BTreeMap<String, Vec<LibPin>> = BTreeMap::new();
    for sym in top
        .child("lib_symbols")
        .ok_or("no lib_symbols")?
        .children("symbol")
    {
        let name = sym
            .text(1)
            .ok_or("a lib symbol without a name")?
            .to_string();
        let mut pins = Vec::new();
        for unit in sym.children("symbol") {
            let uname = unit.text(1).ok_or("a unit without a name")?;
            let mut parts = uname.rsplitn(3, '_');
            let style: i64 = parts
                .next()
                .and_then(|s| s.parse().ok())
                .ok_or(format!("unit name {uname:?}"))?;
            let unit_no: i64 = parts
                .next()
                .and_then(|s| s.parse().ok())
                .ok_or(format!("unit name {uname:?}"))?;
            for p in unit.children("pin") {
                let at = p.child("at").ok_or(format!("a pin of {name} without at"))?;
                pins.push(LibPin {
                    number: p
                        .child("number")
                        .and_then(|n| n.text(1))
                        .ok_or(format!("a pin of {name} without a number"))?
                        .to_string(),
                    name: p
                        .child("name")
                        .and_then(|n| n.text(1))
                        .ok_or(format!("a pin of {name} without a name"))?
                        .to_string(),
                    at: (iu(at.num(1)?), iu(at.num(2)?)),
                    unit: unit_no,
                    style,
                });
            }
        }
        lib.insert(name, pins);
    }
    let mut symbols = Vec::new();
    for s in top.children("symbol") {
        let lib_id = s
            .child("lib_id")
            .and_then(|l| l.text(1))
            .ok_or("a symbol without lib_id")?
            .to_string();
        let prop = |key: &str| {
            s.children("property")
                .find(|p| p.text(1) == Some(key))
                .and_then(|p| p.text(2))
                .map(str::to_string)
        };
        let reference = prop("Reference").ok_or(format!("a {lib_id} without a Reference"))?;
        let value = prop("Value").unwrap_or_default();
        let at = s.child("at").ok_or(format!("{reference} has no at"))?;
        let pos = (iu(at.num(1)?), iu(at.num(2)?));
        let angle = if at.items().len() > 3 {
            at.num(3)?.round() as i64
        } else {
            0
        };
        let mirror = s.child("mirror").and_then(|m| m.text(1));
        let unit = match s.child("unit") {
            Some(u) => u.num(1)? as i64,
            None => 1,
        };
        let lib_pins = lib
            .get(&lib_id)
            .ok_or(format!("{reference}: {lib_id} is not in lib_symbols"))?;
        let mut pins = Vec::new();
        for p in lib_pins {
            if (p.unit == 0 || p.unit == unit) && (p.style == 0 || p.style == 1) {
                let point = pin_on_sheet(p.at, pos, angle, mirror)
                    .map_err(|e| format!("{reference}: {e}"))?;
                pins.push((p.number.clone(), p.name.clone(), point));
            }
        }
        symbols.push(Placed {
            reference,
            lib_id,
            value,
            pins,
        });
    }
    let mut labels = Vec::new();
    for kind in ["label", "global_label"] {
        for l in top.children(kind) {
            let name = l.text(1).ok_or("a label without text")?.to_string();
            let at = l.child("at").ok_or(format!("label {name} has no at"))?;
            labels.push((name, (iu(at.num(1)?), iu(at.num(2)?))));
        }
    }
    let mut no_connects = Vec::new();
    for n in top.children("no_connect") {
        let at = n.child("at").ok_or("a no_connect without at")?;
        no_connects.push((iu(at.num(1)?), iu(at.num(2)?)));
    }
    let mut instance_refs = BTreeSet::new();
    if let Some(inst) = top.child("symbol_instances") {
        for p in inst.children("path") {
            if let Some(r) = p.child("reference").and_then(|r| r.text(1)) {
                instance_refs.insert(r.to_string());
            }
        }
    }
    Ok(Schematic {
        symbols,
        labels,
        no_connects,
        instance_refs,
    })
}

// ---------------------------------------------------------------------------
// The netlist
// ---------------------------------------------------------------------------

/// One pin of one symbol: (reference, number, name).
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord)]
struct PinRef {
    reference: String,
    number: String,
    name: String,
}

impl std::fmt::Display for PinRef {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}.{} ({})", self.reference, self.name, self.number)
    }
}

#[derive(Debug)]
struct Netlist {
    symbols: Vec<Placed>,
    /// net name -> its pins
    nets: BTreeMap<String, BTreeSet<PinRef>>,
    /// (reference, pin number) -> net name; a pin marked no-connect is absent
    net_of: BTreeMap<(String, String), String>,
}

/// Joins every pin to the label on its connection point. Every pin must have
/// exactly one label or a no-connect mark; every label and mark must sit on
/// a pin; no two pins may touch (KiCad would join them without a label).
fn netlist(sch: Schematic) -> Result<Netlist, Vec<String>> {
    let mut problems = Vec::new();
    let mut at_point: BTreeMap<Point, Vec<PinRef>> = BTreeMap::new();
    for s in &sch.symbols {
        for (number, name, p) in &s.pins {
            at_point.entry(*p).or_default().push(PinRef {
                reference: s.reference.clone(),
                number: number.clone(),
                name: name.clone(),
            });
        }
    }
    for (p, pins) in &at_point {
        if pins.len() > 1 {
            let list: Vec<String> = pins.iter().map(|p| p.to_string()).collect();
            problems.push(format!("pins touch at {p:?}: {}", list.join(", ")));
        }
    }
    let mut labels_at: BTreeMap<Point, Vec<&str>> = BTreeMap::new();
    for (name, p) in &sch.labels {
        labels_at.entry(*p).or_default().push(name);
        if !at_point.contains_key(p) {
            problems.push(format!(
                "label {name:?} at ({:.2}, {:.2}) mm is on no pin's end",
                p.0 as f64 / 1e4,
                p.1 as f64 / 1e4
            ));
        }
    }
    let ncs: BTreeSet<Point> = sch.no_connects.iter().copied().collect();
    for p in &ncs {
        if !at_point.contains_key(p) {
            problems.push(format!("a no-connect mark at {p:?} is on no pin"));
        }
    }
    let mut nets: BTreeMap<String, BTreeSet<PinRef>> = BTreeMap::new();
    let mut net_of = BTreeMap::new();
    for (p, pins) in &at_point {
        let names: BTreeSet<&str> = labels_at
            .get(p)
            .map(|v| v.iter().copied().collect())
            .unwrap_or_default();
        for pin in pins {
            match (names.len(), ncs.contains(p)) {
                (0, false) => problems.push(format!("{pin} has no label on its end")),
                (0, true) => {}
                (1, false) => {
                    let net = names
                        .iter()
                        .next()
                        .map(|s| s.to_string())
                        .unwrap_or_default();
                    nets.entry(net.clone()).or_default().insert(pin.clone());
                    net_of.insert((pin.reference.clone(), pin.number.clone()), net);
                }
                (_, true) => problems.push(format!("{pin} has a label and a no-connect mark")),
                (_, false) => problems.push(format!("{pin} has two labels: {names:?}")),
            }
        }
    }
    for (net, pins) in &nets {
        if pins.len() < 2 {
            let only: Vec<String> = pins.iter().map(|p| p.to_string()).collect();
            problems.push(format!("net {net:?} has one pin only: {}", only.join(", ")));
        }
    }
    let refs: BTreeSet<String> = sch.symbols.iter().map(|s| s.reference.clone()).collect();
    if refs.len() != sch.symbols.len() {
        problems.push("two symbols share a reference".into());
    }
    if !sch.instance_refs.is_empty() && sch.instance_refs != refs {
        problems.push(format!(
            "symbol_instances names {:?}, the symbols are {:?}",
            sch.instance_refs, refs
        ));
    }
    if problems.is_empty() {
        Ok(Netlist {
            symbols: sch.symbols,
            nets,
            net_of,
        })
    } else {
        Err(problems)
    }
}

fn repo_path(rel: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .join(rel)
}

fn read(rel: &str) -> String {
    let path = repo_path(rel);
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

fn load() -> Netlist {
    let sch = read_schematic(&read("hardware/ppmc-bridge.kicad_sch"))
        .unwrap_or_else(|e| panic!("hardware/ppmc-bridge.kicad_sch: {e}"));
    netlist(sch).unwrap_or_else(|problems| {
        panic!(
            "hardware/ppmc-bridge.kicad_sch does not give a netlist:\n  {}",
            problems.join("\n  ")
        )
    })
}

const GND: &str = "GND";
const V3: &str = "+3V3";
const V5_CHIP: &str = "+5V_CHIP";
const VBUS: &str = "VBUS";

fn is_passive(part: &str) -> bool {
    matches!(part, "R" | "C")
}

impl Netlist {
    fn only(&self, part: &str) -> Result<&Placed, String> {
        let found: Vec<&Placed> = self.symbols.iter().filter(|s| s.part() == part).collect();
        match found.as_slice() {
            [one] => Ok(one),
            _ => Err(format!("{} symbols of {part}, not one", found.len())),
        }
    }
    fn all(&self, part: &str) -> Vec<&Placed> {
        self.symbols.iter().filter(|s| s.part() == part).collect()
    }
    fn symbol(&self, reference: &str) -> Option<&Placed> {
        self.symbols.iter().find(|s| s.reference == reference)
    }
    /// The pin called `name` of `sym` (one only).
    fn pin(&self, sym: &Placed, name: &str) -> Result<PinRef, String> {
        let found: Vec<&(String, String, Point)> =
            sym.pins.iter().filter(|(_, n, _)| n == name).collect();
        match found.as_slice() {
            [(number, name, _)] => Ok(PinRef {
                reference: sym.reference.clone(),
                number: number.clone(),
                name: name.clone(),
            }),
            _ => Err(format!(
                "{} has {} pins called {name:?}",
                sym.reference,
                found.len()
            )),
        }
    }
    fn net(&self, pin: &PinRef) -> Result<&str, String> {
        self.net_of
            .get(&(pin.reference.clone(), pin.number.clone()))
            .map(String::as_str)
            .ok_or(format!("{pin} is on no net"))
    }
    fn members(&self, net: &str) -> BTreeSet<PinRef> {
        self.nets.get(net).cloned().unwrap_or_default()
    }
    /// The net's pins that are not resistors or capacitors.
    fn active(&self, net: &str) -> BTreeSet<PinRef> {
        self.members(net)
            .into_iter()
            .filter(|p| {
                self.symbol(&p.reference)
                    .is_some_and(|s| !is_passive(s.part()))
            })
            .collect()
    }
    /// For each two-pin part of kind `part` with one end on `net`: (the part,
    /// the net of its other end).
    fn across(&self, net: &str, part: &str) -> Vec<(String, String)> {
        let mut out = Vec::new();
        for p in self.members(net) {
            let Some(sym) = self.symbol(&p.reference) else {
                continue;
            };
            if sym.part() != part {
                continue;
            }
            for (number, _, _) in &sym.pins {
                if *number != p.number {
                    if let Some(other) = self.net_of.get(&(sym.reference.clone(), number.clone())) {
                        out.push((sym.reference.clone(), other.clone()));
                    }
                }
            }
        }
        out
    }
}

// ---------------------------------------------------------------------------
// The pin map
// ---------------------------------------------------------------------------

#[derive(Debug, Clone, Copy, PartialEq)]
enum Way {
    /// Bridge to chip, through a 74AHCT244 (A in, Y out).
    ToChip,
    /// Chip to bridge, through a 74LVC245 (A in from the chip, B out).
    FromChip,
    /// D0-D7, through the 74LVC8T245 (A on the bridge, B on the chip).
    Data,
}

/// Every signal of the chip's header that a GPIO of the pin map serves:
/// (the header pin's name, the GPIO, the way).
fn signals() -> Vec<(String, u32, Way)> {
    let mut v = Vec::new();
    for i in 0..8 {
        v.push((format!("D{i}"), pins::D0 + i, Way::Data));
    }
    for (name, g) in [
        ("A0", pins::A0),
        ("CS*", pins::CS),
        ("RD*", pins::RD),
        ("WR*", pins::WR),
        ("RESET*", pins::RESET),
    ] {
        v.push((name.to_string(), g, Way::ToChip));
    }
    // pins::INPUTS is in ppmc_core::protocol::Input::ALL's order.
    let inputs = [
        "L1*", "L2*", "L3*", "L4*", "ALM*", "CNP*", "AUXI0", "AUXI1", "AUXI2", "AUXI3",
    ];
    for (name, g) in inputs.iter().zip(pins::INPUTS) {
        v.push((name.to_string(), g, Way::ToChip));
    }
    for (name, g) in [
        ("POUT", pins::POUT),
        ("DIR", pins::DIR),
        ("INT*", pins::INT),
        ("HOLD", pins::HOLD),
        ("AUX*", pins::AUX),
        ("CSEL", pins::CSEL),
        ("VSEL", pins::VSEL),
    ] {
        v.push((name.to_string(), g, Way::FromChip));
    }
    for (i, g) in pins::S.iter().enumerate() {
        v.push((format!("S{}", i + 1), *g, Way::FromChip));
    }
    for (i, g) in pins::AUXO.iter().enumerate() {
        v.push((format!("AUXO{i}"), *g, Way::FromChip));
    }
    v
}

/// Every GPIO the pin map uses, with its name.
fn gpios() -> Vec<(String, u32)> {
    let mut v: Vec<(String, u32)> = signals().into_iter().map(|(n, g, _)| (n, g)).collect();
    v.push(("SHIFT_DIR".into(), pins::SHIFT_DIR));
    v.push(("CAPTURE_OE".into(), pins::CAPTURE_OE));
    v.push(("TEST_GEN".into(), pins::TEST_GEN));
    v.push(("DRIVE_EN".into(), pins::DRIVE_EN));
    v
}

/// The other end of a buffer channel: 1A3 <-> 1Y3 on a 74AHCT244, A3 <-> B3
/// on a 74LVC245 or 74LVC8T245. None for a pin that is no channel's end.
fn channel_partner(part: &str, name: &str) -> Option<String> {
    match part {
        "74AHCT244" => {
            let (group, rest) = name.split_at(1);
            let n = rest.strip_prefix('A').or_else(|| rest.strip_prefix('Y'))?;
            if !matches!(group, "1" | "2") || !matches!(n, "1" | "2" | "3" | "4") {
                return None;
            }
            let other = if rest.starts_with('A') { 'Y' } else { 'A' };
            Some(format!("{group}{other}{n}"))
        }
        "74LVC245" | "74LVC8T245" => {
            let n = name.strip_prefix('A').or_else(|| name.strip_prefix('B'))?;
            if !matches!(n.parse::<u32>(), Ok(1..=8)) {
                return None;
            }
            let other = if name.starts_with('A') { 'B' } else { 'A' };
            Some(format!("{other}{n}"))
        }
        _ => None,
    }
}

fn report(what: &str, problems: Vec<String>) {
    assert!(problems.is_empty(), "{what}:\n  {}", problems.join("\n  "));
}

/// Checks one signal: the GPIO's net holds the module's pin and one buffer
/// pin; the buffer's other end is on the net of the header's pin, which
/// holds nothing else; the buffer is the right kind and faces the right way.
fn check_signal(
    nl: &Netlist,
    name: &str,
    gpio: u32,
    way: Way,
    problems: &mut Vec<String>,
) -> Result<(String, String), String> {
    let module = nl.only("PGA2350")?;
    let header = nl.only("ChipHeader_2x25")?;
    let gp = nl.pin(module, &format!("GP{gpio}"))?;
    let hp = nl.pin(header, name)?;
    let gnet = nl
        .net(&gp)
        .map_err(|e| format!("{name} (GPIO {gpio}): {e}"))?;
    let hnet = nl.net(&hp).map_err(|e| format!("{name}: {e}"))?;
    let others: Vec<PinRef> = nl.active(gnet).into_iter().filter(|p| *p != gp).collect();
    let [buf_pin] = others.as_slice() else {
        return Err(format!(
            "{name}: GPIO {gpio}'s net {gnet:?} should hold one buffer pin, it holds {}",
            others
                .iter()
                .map(|p| p.to_string())
                .collect::<Vec<_>>()
                .join(", ")
        ));
    };
    let buf = nl
        .symbol(&buf_pin.reference)
        .ok_or(format!("{buf_pin}: no such symbol"))?;
    let (want_part, gpio_side) = match way {
        Way::ToChip => ("74AHCT244", 'A'),
        Way::FromChip => ("74LVC245", 'B'),
        Way::Data => ("74LVC8T245", 'A'),
    };
    if buf.part() != want_part {
        problems.push(format!(
            "{name}: GPIO {gpio} goes to a {} ({buf_pin}), not a {want_part}",
            buf.part()
        ));
    }
    let side_ok = match buf.part() {
        "74AHCT244" => buf_pin.name.chars().nth(1) == Some(gpio_side),
        _ => buf_pin.name.starts_with(gpio_side),
    };
    if !side_ok {
        problems.push(format!(
            "{name}: GPIO {gpio} is on {buf_pin}, the wrong side of the buffer for {way:?}"
        ));
    }
    let partner_name = channel_partner(buf.part(), &buf_pin.name)
        .ok_or(format!("{name}: {buf_pin} is not a buffer channel's end"))?;
    let partner = nl.pin(buf, &partner_name)?;
    let pnet = nl.net(&partner)?;
    if pnet != hnet {
        problems.push(format!(
            "{name}: GPIO {gpio} goes through {buf_pin} to {partner} (net {pnet:?}), \
             but the header's {name} is on {hnet:?}"
        ));
    }
    let want: BTreeSet<PinRef> = [hp.clone(), partner.clone()].into_iter().collect();
    let got = nl.active(hnet);
    if got != want {
        problems.push(format!(
            "{name}: the header's net {hnet:?} should hold {hp} and {partner} only, it holds {}",
            got.iter()
                .map(|p| p.to_string())
                .collect::<Vec<_>>()
                .join(", ")
        ));
    }
    Ok((gnet.to_string(), hnet.to_string()))
}

// ---------------------------------------------------------------------------
// Tests
// ---------------------------------------------------------------------------

/// The transform against KiCad's own cases: a resistor (pin 1 at (0, 3.81)
/// in the library, Y up) placed at (100, 50) has pin 1 above its centre on
/// the sheet (Y down); rotated 90 degrees (counter-clockwise on screen) pin
/// 1 is on the left; mirrored about X it is below.
#[test]
fn the_transform_follows_kicad() {
    let p1 = (0, iu(3.81));
    let at = (iu(100.0), iu(50.0));
    let mm = |x: f64, y: f64| (iu(x), iu(y));
    let cases = [
        (0, None, p1, mm(100.0, 46.19)),
        (90, None, p1, mm(96.19, 50.0)),
        (180, None, p1, mm(100.0, 53.81)),
        (270, None, p1, mm(103.81, 50.0)),
        (0, Some("x"), p1, mm(100.0, 53.81)),
        (0, Some("y"), (iu(-5.08), 0), mm(105.08, 50.0)),
        // A pin on the right (5.08, 0), rotated 90 (now above), then flipped
        // on the sheet about X: below.
        (90, Some("x"), (iu(5.08), 0), mm(100.0, 55.08)),
        // Rotated 90 (above), flipped about Y: X unchanged (0).
        (90, Some("y"), (iu(5.08), 0), mm(100.0, 44.92)),
    ];
    for (angle, mirror, pin, want) in cases {
        assert_eq!(
            pin_on_sheet(pin, at, angle, mirror),
            Ok(want),
            "angle {angle}, mirror {mirror:?}"
        );
    }
    assert!(pin_on_sheet(p1, at, 45, None).is_err());
}

#[test]
fn the_reader_reads_what_kicad_writes() {
    let sx = parse_sx(r#"(a (b "x \"y\"" 1.5) c)"#).expect("parses");
    assert_eq!(sx.head(), Some("a"));
    assert_eq!(sx.child("b").and_then(|b| b.text(1)), Some("x \"y\""));
    assert_eq!(sx.child("b").map(|b| b.num(2)), Some(Ok(1.5)));
    assert!(parse_sx("(a (b)").is_err());
    assert!(parse_sx("(a))").is_err());
    // A label moved off its pin, and a pin with no label, are both found.
    let sch = r#"(kicad_sch (version 20211123) (generator t)
      (lib_symbols (symbol "t:R" (symbol "R_1_1"
        (pin passive line (at 0 3.81 270) (length 1.27) (name "~") (number "1"))
        (pin passive line (at 0 -3.81 90) (length 1.27) (name "~") (number "2")))))
      (label "A" (at 10 6.19 0)) (label "B" (at 10 13.81 0)) (label "A" (at 20 6.19 0))
      (symbol (lib_id "t:R") (at 10 10 0) (unit 1) (property "Reference" "R1"))
      (symbol (lib_id "t:R") (at 20 10 0) (unit 1) (property "Reference" "R2")))"#;
    let problems = netlist(read_schematic(sch).expect("reads")).expect_err("R2.2 has no label");
    assert_eq!(problems.len(), 2, "{problems:?}");
    assert!(problems.iter().any(|p| p.contains("R2.~ (2) has no label")));
    assert!(problems
        .iter()
        .any(|p| p.contains("net \"B\" has one pin only")));
}

#[test]
fn every_pin_has_its_label_and_every_label_its_pin() {
    let nl = load();
    assert!(nl.nets.len() > 60, "{} nets", nl.nets.len());
}

#[test]
fn every_gpio_of_the_pin_map_reaches_its_signal_on_the_chip_header() {
    let nl = load();
    let mut problems = Vec::new();
    let mut gpio_nets: BTreeMap<String, String> = BTreeMap::new();
    let mut chip_nets: BTreeMap<String, String> = BTreeMap::new();
    for (name, gpio, way) in signals() {
        match check_signal(&nl, &name, gpio, way, &mut problems) {
            Ok((gnet, hnet)) => {
                if let Some(other) = gpio_nets.insert(gnet.clone(), name.clone()) {
                    problems.push(format!("{name} and {other} share the GPIO net {gnet:?}"));
                }
                if let Some(other) = chip_nets.insert(hnet.clone(), name.clone()) {
                    problems.push(format!("{name} and {other} share the chip's net {hnet:?}"));
                }
            }
            Err(e) => problems.push(e),
        }
    }
    // A GPIO used twice in the map, and a GPIO outside the map that the
    // schematic connects.
    let mut used: BTreeMap<u32, String> = BTreeMap::new();
    for (name, g) in gpios() {
        if let Some(other) = used.insert(g, name.clone()) {
            problems.push(format!(
                "GPIO {g} is both {other} and {name} in the pin map"
            ));
        }
    }
    let module = nl.only("PGA2350").expect("one PGA2350");
    for g in 0..48u32 {
        let pin = nl
            .pin(module, &format!("GP{g}"))
            .expect("the module has GP0-GP47");
        match (used.get(&g), nl.net(&pin)) {
            (Some(name), Err(_)) => problems.push(format!("GPIO {g} ({name}) is not connected")),
            (None, Ok(net)) => problems.push(format!(
                "GPIO {g} is on net {net:?} but not in the pin map (mark it no-connect)"
            )),
            _ => {}
        }
    }
    report("the pin map against the schematic", problems);
}

/// GPIO 47 is the PGA2350's PSRAM chip select (the Pico SDK's
/// `boards/pimoroni_pga2350.h`: `PIMORONI_PGA2350_PSRAM_CS_PIN 47`). A
/// signal from the chip's board on it would select the PSRAM while the
/// RP2350 reads its flash on the same QSPI lines: the pin map leaves it
/// free, and the schematic leaves it unconnected.
#[test]
fn gpio_47_the_modules_psram_select_is_left_free() {
    const PSRAM_CS: u32 = 47;
    let mut problems = Vec::new();
    for (name, g) in gpios() {
        if g == PSRAM_CS {
            problems.push(format!(
                "{name} is on GPIO {g}, the PGA2350's PSRAM chip select"
            ));
        }
    }
    let nl = load();
    let module = nl.only("PGA2350").expect("one PGA2350");
    let pin = nl
        .pin(module, &format!("GP{PSRAM_CS}"))
        .expect("the module has GP47");
    if let Ok(net) = nl.net(&pin) {
        problems.push(format!(
            "GPIO {PSRAM_CS}, the PGA2350's PSRAM chip select, is on net {net:?}"
        ));
    }
    report("GPIO 47, the PSRAM's chip select", problems);
}

#[test]
fn the_control_pins_reach_their_parts() {
    let nl = load();
    let mut problems = Vec::new();
    let module = nl.only("PGA2350").expect("one PGA2350");
    let gp = |g: u32| nl.pin(module, &format!("GP{g}")).expect("a GPIO pin");
    let net = |p: &PinRef| nl.net(p).map(str::to_string).unwrap_or_else(|e| e);
    let set = |v: Vec<PinRef>| v.into_iter().collect::<BTreeSet<PinRef>>();
    let shifter = nl.only("74LVC8T245").expect("one 74LVC8T245");
    let hcts = nl.all("74AHCT244");
    let lvcs = nl.all("74LVC245");
    let fet = nl.only("Q_NMOS_GSD").expect("one N-MOSFET");
    let tg_buf = nl.only("74LVC2G126").expect("one 74LVC2G126");
    let mut expect_active = |what: &str, net: &str, want: BTreeSet<PinRef>| {
        let got = nl.active(net);
        if got != want {
            problems.push(format!(
                "{what}: net {net:?} holds {}, not {}",
                got.iter()
                    .map(|p| p.to_string())
                    .collect::<Vec<_>>()
                    .join(", "),
                want.iter()
                    .map(|p| p.to_string())
                    .collect::<Vec<_>>()
                    .join(", ")
            ));
        }
    };
    // SHIFT_DIR: the shifter's DIR, pulled down (the shifter faces the
    // bridge while the bridge boots).
    let dir_net = net(&gp(pins::SHIFT_DIR));
    expect_active(
        "SHIFT_DIR",
        &dir_net,
        set(vec![
            gp(pins::SHIFT_DIR),
            nl.pin(shifter, "DIR").expect("DIR"),
        ]),
    );
    // CAPTURE_OE: OE* of every 74LVC245 (low: on), and OE of both of the
    // 74LVC2G126's buffers (high: on), pulled up to 3.3 V: TEST_GEN reaches
    // the capture inputs only while the chip's outputs are cut off.
    let oe_net = net(&gp(pins::CAPTURE_OE));
    let mut want = vec![gp(pins::CAPTURE_OE)];
    want.extend(lvcs.iter().map(|u| nl.pin(u, "OE*").expect("OE*")));
    want.push(nl.pin(tg_buf, "1OE").expect("1OE"));
    want.push(nl.pin(tg_buf, "2OE").expect("2OE"));
    expect_active("CAPTURE_OE", &oe_net, set(want));
    // DRIVE_EN: the MOSFET's gate (pulled down); its drain holds OE* of every
    // 74AHCT244 (pulled up to the chip's 5 V); its source is on GND.
    let en_net = net(&gp(pins::DRIVE_EN));
    expect_active(
        "DRIVE_EN",
        &en_net,
        set(vec![gp(pins::DRIVE_EN), nl.pin(fet, "G").expect("G")]),
    );
    let drain = nl.pin(fet, "D").expect("D");
    let drain_net = net(&drain);
    let mut want = vec![drain.clone()];
    for u in &hcts {
        want.push(nl.pin(u, "1OE*").expect("1OE*"));
        want.push(nl.pin(u, "2OE*").expect("2OE*"));
    }
    expect_active("the 74AHCT244s' OE*", &drain_net, set(want));
    // TEST_GEN: the inputs of the 74LVC2G126's two buffers, each buffer's
    // output through 1 kOhm to one capture input (1Y to POUT's, 2Y to
    // INT*'s), so that nothing joins the two capture nets: TEST_GEN's
    // resistors straight to both (earlier revisions) joined them through
    // 2 kOhm whenever TEST_GEN was undriven.
    let tg_net = net(&gp(pins::TEST_GEN));
    expect_active(
        "TEST_GEN",
        &tg_net,
        set(vec![
            gp(pins::TEST_GEN),
            nl.pin(tg_buf, "1A").expect("1A"),
            nl.pin(tg_buf, "2A").expect("2A"),
        ]),
    );
    let mut extra = Vec::new();
    for (out, signal, g) in [("1Y", "POUT", pins::POUT), ("2Y", "INT*", pins::INT)] {
        let y = nl.pin(tg_buf, out).expect("an output");
        let y_net = net(&y);
        expect_active(&format!("the 74LVC2G126's {out}"), &y_net, set(vec![y]));
        let ends = nl.across(&y_net, "R");
        match ends.as_slice() {
            [(r, end)] if *end == net(&gp(g)) => {
                let value = nl.symbol(r).map(|s| s.value.clone()).unwrap_or_default();
                if value != "1k" {
                    extra.push(format!(
                        "{r} from the 74LVC2G126's {out} is {value}, not 1k: a firmware that drove TEST_GEN with the capture on would meet the 74LVC245s"
                    ));
                }
            }
            other => extra.push(format!(
                "the 74LVC2G126's {out} reaches {other:?} through resistors, not {signal}'s GPIO net alone"
            )),
        }
    }
    if nl
        .across(&tg_net, "R")
        .iter()
        .any(|(_, end)| *end == net(&gp(pins::POUT)) || *end == net(&gp(pins::INT)))
    {
        extra.push("a resistor joins TEST_GEN to a capture input directly".into());
    }
    problems.extend(extra);
    if nl.net(&nl.pin(fet, "S").expect("S")).ok() != Some(GND) {
        problems.push("the MOSFET's source is not on GND".into());
    }
    // The 74LVC245s pass A (the chip) to B (the bridge): DIR high.
    for u in &lvcs {
        if nl.net(&nl.pin(u, "DIR").expect("DIR")).ok() != Some(V3) {
            problems.push(format!(
                "{}'s DIR is not tied to {V3} (A to B)",
                u.reference
            ));
        }
    }
    if nl.net(&nl.pin(shifter, "OE*").expect("OE*")).ok() != Some(GND) {
        problems.push("the 74LVC8T245's OE* is not tied to GND".into());
    }
    report("the control pins", problems);
}

/// While DRIVE_EN is low or the bridge is off, the 74AHCT244s are off and
/// resistors hold the chip's inputs: RESET* low, every other one high.
#[test]
fn the_chip_is_held_safe_while_the_bridge_boots_or_is_off() {
    let nl = load();
    let mut problems = Vec::new();
    let module = nl.only("PGA2350").expect("one PGA2350");
    let fet = nl.only("Q_NMOS_GSD").expect("one N-MOSFET");
    let header = nl.only("ChipHeader_2x25").expect("one header");
    let net_of_pin = |sym: &Placed, name: &str| {
        nl.pin(sym, name)
            .and_then(|p| nl.net(&p).map(str::to_string))
            .unwrap_or_else(|e| e)
    };
    let pulls = |net: &str| -> Vec<String> {
        nl.across(net, "R")
            .into_iter()
            .map(|(_, other)| other)
            .filter(|o| o == GND || o == V3 || o == V5_CHIP)
            .collect()
    };
    let mut want_pull = |what: &str, net: &str, to: &str| {
        let got = pulls(net);
        if got != [to] {
            problems.push(format!(
                "{what} (net {net:?}) is pulled to {got:?}, not to {to} alone"
            ));
        }
    };
    want_pull("the 74AHCT244s' OE*", &net_of_pin(fet, "D"), V5_CHIP);
    want_pull("DRIVE_EN", &net_of_pin(fet, "G"), GND);
    want_pull(
        "CAPTURE_OE",
        &net_of_pin(module, &format!("GP{}", pins::CAPTURE_OE)),
        V3,
    );
    // TEST_GEN is undriven but in the self-test, and the 74LVC2G126 is on
    // whenever the capture is off (the bridge booting, too): held low, its
    // inputs do not float.
    want_pull(
        "TEST_GEN",
        &net_of_pin(module, &format!("GP{}", pins::TEST_GEN)),
        GND,
    );
    want_pull(
        "SHIFT_DIR",
        &net_of_pin(module, &format!("GP{}", pins::SHIFT_DIR)),
        GND,
    );
    for (name, _, way) in signals() {
        let net = net_of_pin(header, &name);
        match (way, name.as_str()) {
            (Way::ToChip, "RESET*") => want_pull(&name, &net, GND),
            (Way::ToChip, _) => want_pull(&name, &net, V5_CHIP),
            (Way::FromChip, "CSEL" | "VSEL") => want_pull(&name, &net, V5_CHIP),
            _ => {}
        }
    }
    report("the safe state", problems);
}

fn farads(value: &str) -> Option<f64> {
    let v = value.trim_end_matches('F');
    let (num, scale) = match v.chars().last()? {
        'p' => (&v[..v.len() - 1], 1e-12),
        'n' => (&v[..v.len() - 1], 1e-9),
        'u' | '\u{b5}' => (&v[..v.len() - v.chars().last()?.len_utf8()], 1e-6),
        'm' => (&v[..v.len() - 1], 1e-3),
        _ => (v, 1.0),
    };
    num.parse::<f64>().ok().map(|n| n * scale)
}

#[test]
fn every_ic_has_its_supplies_and_a_decoupling_capacitor() {
    let nl = load();
    let mut problems = Vec::new();
    let supplies: [(&str, &[(&str, &str)]); 5] = [
        ("74AHCT244", &[("VCC", V5_CHIP)]),
        ("74LVC245", &[("VCC", V3)]),
        ("74LVC2G126", &[("VCC", V3)]),
        ("74LVC8T245", &[("VCCA", V3), ("VCCB", V5_CHIP)]),
        ("PGA2350", &[("VB", VBUS), ("3V3", V3)]),
    ];
    // (supply net) -> the ICs' supply pins on it that want a 100 nF each
    let mut want_caps: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for (part, pins) in supplies {
        let syms = nl.all(part);
        if syms.is_empty() {
            problems.push(format!("no {part} in the schematic"));
        }
        for s in syms {
            for (name, net) in pins.iter() {
                for (number, pname, _) in s.pins.iter().filter(|(_, n, _)| n == name) {
                    let got = nl.net_of.get(&(s.reference.clone(), number.clone()));
                    if got.map(String::as_str) != Some(*net) {
                        problems.push(format!(
                            "{}.{pname} ({number}) is on {got:?}, not {net}",
                            s.reference
                        ));
                    }
                }
                if s.reference.starts_with('U') {
                    want_caps
                        .entry(net.to_string())
                        .or_default()
                        .insert(format!("{}.{name}", s.reference));
                }
            }
            for (number, pname, _) in s.pins.iter().filter(|(_, n, _)| n == "GND") {
                let got = nl.net_of.get(&(s.reference.clone(), number.clone()));
                if got.map(String::as_str) != Some(GND) {
                    problems.push(format!(
                        "{}.{pname} ({number}) is on {got:?}, not GND",
                        s.reference
                    ));
                }
            }
        }
    }
    // Every IC ("U") is one of the parts above.
    for s in nl.symbols.iter().filter(|s| s.reference.starts_with('U')) {
        if !supplies.iter().any(|(p, _)| *p == s.part()) {
            problems.push(format!(
                "{} ({}) has no supply rule in this test",
                s.reference,
                s.part()
            ));
        }
    }
    let caps_between = |net: &str| -> Vec<f64> {
        nl.across(net, "C")
            .into_iter()
            .filter(|(_, other)| other == GND)
            .filter_map(|(r, _)| nl.symbol(&r).and_then(|s| farads(&s.value)))
            .collect()
    };
    for (net, ics) in &want_caps {
        let caps = caps_between(net);
        let small = caps.iter().filter(|f| (**f - 100e-9).abs() < 1e-12).count();
        if small < ics.len() {
            problems.push(format!(
                "{net} feeds {} ({}) but has {small} 100 nF capacitor(s) to GND",
                ics.len(),
                ics.iter().cloned().collect::<Vec<_>>().join(", ")
            ));
        }
    }
    for net in [V3, V5_CHIP, VBUS] {
        if !caps_between(net).iter().any(|f| *f >= 1e-6) {
            problems.push(format!("{net} has no bulk capacitor (1 uF or more) to GND"));
        }
    }
    report("supplies and decoupling", problems);
}

/// A CSV line's fields ("a,\"b, c\",d").
fn csv_fields(line: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut cur = String::new();
    let mut quoted = false;
    let mut chars = line.chars().peekable();
    while let Some(c) = chars.next() {
        match (c, quoted) {
            ('"', true) if chars.peek() == Some(&'"') => {
                cur.push('"');
                chars.next();
            }
            ('"', _) => quoted = !quoted,
            (',', false) => out.push(std::mem::take(&mut cur)),
            _ => cur.push(c),
        }
    }
    out.push(cur);
    out
}

#[test]
fn the_parts_list_and_the_schematic_name_the_same_parts() {
    let nl = load();
    let text = read("hardware/bom.csv");
    let mut lines = text.lines().filter(|l| !l.trim().is_empty());
    let head = csv_fields(lines.next().expect("a header row"));
    let col = |name: &str| {
        head.iter()
            .position(|h| h == name)
            .unwrap_or_else(|| panic!("hardware/bom.csv has no column {name:?}: {head:?}"))
    };
    let (c_refs, c_qty, c_value, c_pkg) = (
        col("references"),
        col("quantity"),
        col("value"),
        col("package"),
    );
    let c_part = col("part_example");
    let mut problems = Vec::new();
    let mut in_bom: BTreeMap<String, usize> = BTreeMap::new();
    for (i, line) in lines.enumerate() {
        let f = csv_fields(line);
        if f.len() != head.len() {
            problems.push(format!(
                "row {}: {} fields, the header has {}",
                i + 2,
                f.len(),
                head.len()
            ));
            continue;
        }
        let refs: Vec<&str> = f[c_refs].split_whitespace().collect();
        if f[c_qty].parse::<usize>().ok() != Some(refs.len()) {
            problems.push(format!(
                "row {}: quantity {} for {} references",
                i + 2,
                f[c_qty],
                refs.len()
            ));
        }
        if f[c_pkg].trim().is_empty() || f[c_part].trim().is_empty() {
            problems.push(format!("row {}: no package or part example", i + 2));
        }
        for r in refs {
            *in_bom.entry(r.to_string()).or_default() += 1;
            match nl.symbol(r) {
                None => problems.push(format!("{r} is in the BOM but not in the schematic")),
                Some(s) if s.value != f[c_value] => problems.push(format!(
                    "{r} is {:?} in the schematic, {:?} in the BOM",
                    s.value, f[c_value]
                )),
                Some(_) => {}
            }
        }
    }
    for (r, n) in &in_bom {
        if *n > 1 {
            problems.push(format!("{r} is in {n} BOM rows"));
        }
    }
    for s in &nl.symbols {
        if !in_bom.contains_key(&s.reference) {
            problems.push(format!(
                "{} ({}) is in the schematic but not in the BOM",
                s.reference, s.value
            ));
        }
    }
    report("hardware/bom.csv against the schematic", problems);
}

/// The section of `file` under the heading `## {heading}`.
fn doc_section(file: &str, heading: &str) -> String {
    read(file)
        .split("\n## ")
        .find(|s| s.starts_with(heading))
        .unwrap_or_else(|| panic!("{file} has a section \"## {heading}\""))
        .to_string()
}

/// The cells of each row of the tables in `section`, trimmed.
fn table_rows(section: &str) -> Vec<Vec<&str>> {
    section
        .lines()
        .filter(|l| l.starts_with('|'))
        .map(|l| l.trim_matches('|').split('|').map(str::trim).collect())
        .collect()
}

/// Where `sym`'s pins (number and name) and `table`'s (number to name)
/// differ, either way.
fn pins_against_table(
    sym: &Placed,
    table: &BTreeMap<String, String>,
    table_name: &str,
) -> Vec<String> {
    let on_sym: BTreeMap<&str, &str> = sym
        .pins
        .iter()
        .map(|(n, name, _)| (n.as_str(), name.as_str()))
        .collect();
    let mut problems = Vec::new();
    for (pin, name) in &on_sym {
        match table.get(*pin) {
            Some(d) if d == name => {}
            Some(d) => problems.push(format!(
                "pin {pin}: {name} on {}, {d} in {table_name}",
                sym.reference
            )),
            None => problems.push(format!("pin {pin} ({name}) is not in {table_name}")),
        }
    }
    for (pin, name) in table
        .iter()
        .filter(|(p, _)| !on_sym.contains_key(p.as_str()))
    {
        problems.push(format!(
            "pin {pin} ({name}) is in {table_name} but not on {}",
            sym.reference
        ));
    }
    problems
}

/// The connector table of docs/bridge-hardware.md (rows "| 1 | +5V_CHIP | 2 |
/// GND |") is the schematic's header, pin by pin.
#[test]
fn the_doc_shows_the_schematics_header() {
    let nl = load();
    let header = nl.only("ChipHeader_2x25").expect("one header");
    let section = doc_section(
        "docs/bridge-hardware.md",
        "The connector to the chip's board",
    );
    let mut from_doc: BTreeMap<String, String> = BTreeMap::new();
    for cells in table_rows(&section) {
        for pair in cells.chunks(2) {
            if let [pin, signal] = pair {
                if pin.parse::<u32>().is_ok() {
                    from_doc.insert(pin.to_string(), signal.to_string());
                }
            }
        }
    }
    let mut problems = pins_against_table(header, &from_doc, "the doc's table");
    // Every header pin that carries a signal, and its power pins, are on a net.
    for (number, name, _) in &header.pins {
        let net = nl.net_of.get(&(header.reference.clone(), number.clone()));
        let ok = match name.as_str() {
            "GND" => net.map(String::as_str) == Some(GND),
            "+5V_CHIP" => net.map(String::as_str) == Some(V5_CHIP),
            _ => net.is_some(),
        };
        if !ok {
            problems.push(format!("header pin {number} ({name}) is on {net:?}"));
        }
    }
    report("the doc's connector table against the schematic", problems);
}

/// The module has no USB socket and no buttons: the board's USB-C socket
/// reaches its USB pins (through R3/R4), CC1 and CC2 have their 5.1 kOhm
/// each, and the BOOTSEL and RUN buttons pull those pins to GND.
#[test]
fn the_usb_socket_and_the_buttons_reach_the_module() {
    let nl = load();
    let mut problems = Vec::new();
    let module = nl.only("PGA2350").expect("one PGA2350");
    let usb = nl.only("USB_C_USB2").expect("one USB-C socket");
    let net_of = |sym: &Placed, name: &str| -> Vec<String> {
        sym.pins
            .iter()
            .filter(|(_, n, _)| n == name)
            .filter_map(|(number, _, _)| nl.net_of.get(&(sym.reference.clone(), number.clone())))
            .cloned()
            .collect()
    };
    for (module_pin, socket_pin) in [("USB_DP", "D+"), ("USB_DM", "D-")] {
        let socket: BTreeSet<String> = net_of(usb, socket_pin).into_iter().collect();
        let [socket_net] = socket.iter().collect::<Vec<_>>()[..] else {
            problems.push(format!(
                "the socket's {socket_pin} pins are on {socket:?}, not one net"
            ));
            continue;
        };
        let module_net = net_of(module, module_pin);
        let through: Vec<String> = module_net
            .iter()
            .flat_map(|n| nl.across(n, "R"))
            .map(|(_, other)| other)
            .collect();
        if through != [socket_net.clone()] {
            problems.push(format!(
                "the module's {module_pin} reaches {through:?} through a resistor, not the socket's {socket_pin} ({socket_net})"
            ));
        }
    }
    for cc in ["CC1", "CC2"] {
        let pulls: Vec<String> = net_of(usb, cc)
            .iter()
            .flat_map(|n| nl.across(n, "R"))
            .filter(|(_, other)| other == GND)
            .filter_map(|(r, _)| nl.symbol(&r).map(|s| s.value.clone()))
            .collect();
        if pulls != ["5.1k"] {
            problems.push(format!(
                "{cc} is pulled to GND by {pulls:?}, not by one 5.1k"
            ));
        }
    }
    for (name, net) in [("VBUS", VBUS), ("GND", GND), ("SHIELD", GND)] {
        if net_of(usb, name).iter().any(|n| n != net) || net_of(usb, name).is_empty() {
            problems.push(format!(
                "the socket's {name} pins are on {:?}, not {net}",
                net_of(usb, name)
            ));
        }
    }
    // BOOTSEL (through a resistor) and RUN: a button to GND.
    for (pin, via_resistor) in [("BOOTSEL", true), ("RUN", false)] {
        let mut nets = net_of(module, pin);
        if via_resistor {
            nets = nets
                .iter()
                .flat_map(|n| nl.across(n, "R"))
                .map(|(_, other)| other)
                .collect();
        }
        let to_gnd = nets
            .iter()
            .flat_map(|n| nl.across(n, "SW_Push"))
            .any(|(_, other)| other == GND);
        if !to_gnd {
            problems.push(format!("no button pulls the module's {pin} to GND"));
        }
    }
    report("USB and the buttons", problems);
}

/// The PGA2350 symbol's pin numbers are hardware/README.md's table of the
/// module's pins (traced from Pimoroni's pinout diagram), pin by pin: a
/// layout drawn from the symbol puts every signal where the module has it.
#[test]
fn the_modules_pins_are_where_the_readmes_table_puts_them() {
    let nl = load();
    let module = nl.only("PGA2350").expect("one PGA2350");
    let section = doc_section("hardware/README.md", "The PGA2350's pins");
    let mut from_doc: BTreeMap<String, String> = BTreeMap::new();
    for cells in table_rows(&section) {
        let Some((row, pins)) = cells.split_first() else {
            continue;
        };
        if row.len() != 1 || !row.chars().all(|c| c.is_ascii_uppercase()) {
            continue;
        }
        for (col, name) in pins.iter().enumerate() {
            if !name.is_empty() {
                from_doc.insert(format!("{row}{}", col + 1), name.to_string());
            }
        }
    }
    assert_eq!(from_doc.len(), 64, "the table names 64 pins");
    let problems = pins_against_table(module, &from_doc, "the table");
    report("the PGA2350's pins", problems);
}

/// The wiring table of docs/bridge-hardware.md ("A bridge from
/// off-the-shelf parts") as the netlist gives it: a row a net, every point
/// on it. The module's pins are named by GPIO (a breakout or core board
/// labels them so), the others `part.pin`. What a person wires by hand is
/// then the schematic, which the other tests hold to `pins.rs`.
fn wiring_table(nl: &Netlist) -> String {
    let mut out = String::from("| net | wire together |\n|---|---|\n");
    for (net, pins) in &nl.nets {
        // In natural order: R2 before R10, U1.2 before U1.10.
        let natural = |t: &str| {
            let digits = t.trim_start_matches(|c: char| !c.is_ascii_digit());
            let n = digits.parse::<u32>().unwrap_or(0);
            (t[..t.len() - digits.len()].to_string(), n)
        };
        // (the part's sort key, the pin's, the point as written)
        type Entry = ((String, u32), (String, u32), String);
        let mut points: Vec<Entry> = pins
            .iter()
            .map(|p| match nl.symbol(&p.reference).map(Placed::part) {
                Some("PGA2350") => (
                    (String::new(), 0),
                    natural(&p.name),
                    format!("module {}", p.name),
                ),
                _ => (
                    natural(&p.reference),
                    natural(&p.number),
                    format!("{}.{}", p.reference, p.number),
                ),
            })
            .collect();
        points.sort();
        let points: Vec<String> = points.into_iter().map(|(_, _, t)| t).collect();
        out += &format!("| `{net}` | {} |\n", points.join(", "));
    }
    out
}

#[test]
fn the_wiring_table_is_the_schematics_netlist() {
    let nl = load();
    let want = wiring_table(&nl);
    let doc = read("docs/bridge-hardware.md");
    let (begin, end) = (
        "<!-- wiring table: begin -->\n",
        "<!-- wiring table: end -->",
    );
    let got = doc
        .split_once(begin)
        .and_then(|(_, rest)| rest.split_once(end))
        .map(|(table, _)| table)
        .expect("docs/bridge-hardware.md has the wiring table between its two markers");
    assert!(
        got == want,
        "docs/bridge-hardware.md's wiring table differs from the schematic's netlist; the netlist's:\n{want}"
    );
}
