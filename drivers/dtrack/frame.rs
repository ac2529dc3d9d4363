//! One DTrack ASCII datagram, parsed as C++ VRPN parses it, into what the tracker keeps from
//! frame to frame.
//!
//! A datagram is lines separated by CR and/or LF; each line starts with an identifier:
//!
//! | Line | Fields |
//! |---|---|
//! | `fr N` | frame counter |
//! | `ts T` | time of day in seconds since midnight (UTC), with decimals |
//! | `ts2 S U L` | seconds and microseconds since 1970, latency in microseconds (DTRACK3) |
//! | `6dcal N` | number of calibrated targets (bodies, old-format Flysticks, tools) |
//! | `6d N [id q][x y z][r0 .. r8] ...` | standard bodies: quality, position in mm, rotation matrix (column-wise) |
//! | `6df N [id q bits][x y z][r0 .. r8] ...` | Flysticks, old format: 8 buttons as bits, hat in bits 4-7 |
//! | `6df2 C N [id q nb nj][x y z][r0 .. r8][bits.. joy..] ...` | Flysticks: `nb` buttons (32 per word), `nj` joystick values |
//! | `6dmt N ...` | measurement tools: only the count is used |
//! | `3d N [id q][x y z] ...` | single markers |
//!
//! Other identifiers are skipped; a datagram with no line of these is refused (C++ would
//! report the previous frame's targets again). Numbers are read as the C library reads them; a bracketed
//! block is searched from the current position (it may start on a later line, as in C++);
//! extra values inside a block are ignored.
//!
//! What C++ keeps between frames is kept here too: bodies missing from a frame without a
//! `6d` line, Flysticks beyond those in a `6df2` line, the marker list until the next `3d`
//! line. Unlike C++, a datagram that fails to parse changes nothing (C++ keeps the part it
//! had read).

use super::numbers::{strtod, strtol_int, strtoul_uint};

/// Most targets of one kind (bodies, Flysticks, markers) a frame may name; a larger id or
/// count makes the datagram malformed (C++ grows its arrays to any id it reads).
pub const MAX_TARGETS: usize = 256;
/// Most buttons of a `6df2` Flystick.
pub const MAX_FLYSTICK_BUTTONS: usize = 16;
/// Most joystick values of a `6df2` Flystick.
pub const MAX_FLYSTICK_JOYSTICK: usize = 8;

/// A standard body (6DOF).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Body {
    /// Its id (from 0).
    pub id: i32,
    /// 0..1; −1 when not tracked in this frame.
    pub quality: f32,
    /// Position in millimetres.
    pub loc: [f32; 3],
    /// Rotation matrix, column-wise.
    pub rot: [f32; 9],
}

/// A Flystick: a body with buttons and a joystick.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Flystick {
    /// Its id (from 0).
    pub id: i32,
    /// 0..1; −1 when not tracked.
    pub quality: f32,
    /// Buttons the controller sent.
    pub num_button: i32,
    /// 1 pressed, 0 released.
    pub button: [i32; MAX_FLYSTICK_BUTTONS],
    /// Joystick values the controller sent.
    pub num_joystick: i32,
    /// −1..1: 0 horizontal, 1 vertical.
    pub joystick: [f32; MAX_FLYSTICK_JOYSTICK],
    /// Position in millimetres.
    pub loc: [f32; 3],
    /// Rotation matrix, column-wise.
    pub rot: [f32; 9],
}

/// A single marker (3DOF).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Marker {
    /// Its id.
    pub id: i32,
    /// Position in millimetres.
    pub loc: [f32; 3],
}

/// What the tracker knows of the targets, carried from frame to frame as C++ does.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Targets {
    /// Standard bodies, indexed by id (C++ `act_body`, `act_num_body` long).
    pub bodies: Vec<Body>,
    /// Flysticks, indexed by id (only grows, as C++ `act_flystick`).
    pub flysticks: Vec<Flystick>,
    /// Markers of the last `3d` line.
    pub markers: Vec<Marker>,
    /// Calibrated standard bodies (from the last `6dcal` line, less Flysticks and tools).
    pub num_bodycal: i32,
    /// The last Flystick line was `6df` (old format: buttons 1 and 3 swapped for VRPN).
    pub old_flystick_format: bool,
}

impl Targets {
    /// Becomes a copy of `other`, reusing its own lists' storage (no allocation once they
    /// are as long: the derived `clone_from` would allocate new lists).
    pub fn copy_from(&mut self, other: &Targets) {
        self.bodies.clone_from(&other.bodies);
        self.flysticks.clone_from(&other.flysticks);
        self.markers.clone_from(&other.markers);
        self.num_bodycal = other.num_bodycal;
        self.old_flystick_format = other.old_flystick_format;
    }
}

/// The per-frame values of a datagram (C++ resets them for each one).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Header {
    /// `fr`, if the datagram has one.
    pub frame: Option<u32>,
    /// `ts` in seconds since midnight, or −1.
    pub timestamp: f64,
    /// `ts2`: seconds, microseconds, latency in microseconds (seconds 0: none).
    pub ts2: (u32, u32, u32),
    /// The datagram had a `6dcal` line.
    pub has_bodycal: bool,
}

/// Which line of a datagram could not be read.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Malformed {
    /// `fr`.
    Frame,
    /// `ts` or `ts2`.
    Timestamp,
    /// `6dcal`.
    Calibrated,
    /// `6d`.
    Bodies,
    /// `6df` or `6df2`.
    Flysticks,
    /// `6dmt`.
    Tools,
    /// `3d`.
    Markers,
    /// An id or count beyond [`MAX_TARGETS`].
    TooMany,
    /// Nothing in it (C++ takes an empty datagram for a receive error).
    Empty,
    /// No line of it is a DTrack line (C++ would report the last frame's targets again).
    NoDTrackLine,
}

impl Malformed {
    /// The line's identifier, for messages.
    pub fn line(self) -> &'static str {
        match self {
            Malformed::Frame => "fr",
            Malformed::Timestamp => "ts/ts2",
            Malformed::Calibrated => "6dcal",
            Malformed::Bodies => "6d",
            Malformed::Flysticks => "6df/6df2",
            Malformed::Tools => "6dmt",
            Malformed::Markers => "3d",
            Malformed::TooMany => "an id or count above 255",
            Malformed::Empty => "no line",
            Malformed::NoDTrackLine => "no DTrack line",
        }
    }
}

/// Reading position in a datagram.
struct Text<'a> {
    s: &'a [u8],
    pos: usize,
}

impl<'a> Text<'a> {
    fn rest(&self) -> &'a [u8] {
        &self.s[self.pos.min(self.s.len())..]
    }

    fn starts(&self, id: &str) -> bool {
        self.rest().starts_with(id.as_bytes())
    }

    fn int(&mut self) -> Option<i32> {
        let (v, n) = strtol_int(self.rest())?;
        self.pos += n;
        Some(v)
    }

    fn uint(&mut self) -> Option<u32> {
        let (v, n) = strtoul_uint(self.rest())?;
        self.pos += n;
        Some(v)
    }

    fn double(&mut self) -> Option<f64> {
        let (v, n) = strtod(self.rest())?;
        self.pos += n;
        Some(v)
    }

    /// The next `[...]` block from here (C++ `string_get_block`): its inside, and the
    /// position moves past its `]`.
    fn block(&mut self) -> Option<Block<'a>> {
        let rest = self.rest();
        let open = rest.iter().position(|&b| b == b'[')?;
        let close = rest[open..].iter().position(|&b| b == b']')? + open;
        self.pos += close + 1;
        Some(Block {
            s: &rest[open + 1..close],
            pos: 0,
        })
    }

    /// C++ `string_nextline`: past the next CR/LF run; `None` at the end of the datagram.
    fn next_line(&mut self) -> Option<()> {
        let rest = self.rest();
        let eol = rest.iter().position(|&b| b == b'\r' || b == b'\n')?;
        let start = rest[eol..].iter().position(|&b| b != b'\r' && b != b'\n')? + eol;
        self.pos += start;
        Some(())
    }
}

/// The inside of a bracketed block: ints and floats read in order.
struct Block<'a> {
    s: &'a [u8],
    pos: usize,
}

impl Block<'_> {
    fn int(&mut self) -> Option<i32> {
        let (v, n) = strtol_int(&self.s[self.pos..])?;
        self.pos += n;
        Some(v)
    }

    fn float(&mut self) -> Option<f32> {
        let (v, n) = strtod(&self.s[self.pos..])?;
        self.pos += n;
        Some(v as f32)
    }

    fn floats<const N: usize>(&mut self) -> Option<[f32; N]> {
        let mut out = [0.0; N];
        for v in &mut out {
            *v = self.float()?;
        }
        Some(out)
    }
}

fn count(n: i32) -> Result<usize, Malformed> {
    // A negative count reads no entries, as in C++.
    let n = n.max(0) as usize;
    if n > MAX_TARGETS {
        return Err(Malformed::TooMany);
    }
    Ok(n)
}

fn disabled_body(id: usize) -> Body {
    Body {
        id: id as i32,
        quality: -1.0,
        ..Body::default()
    }
}

/// Parses `datagram` (up to its first NUL byte, as C reads a string) into `targets`, which
/// must hold what the previous frames left. On an error `targets` is partly updated: parse
/// into a copy and keep it only on success.
pub fn parse(datagram: &[u8], targets: &mut Targets) -> Result<Header, Malformed> {
    let end = datagram
        .iter()
        .position(|&b| b == 0)
        .unwrap_or(datagram.len());
    let mut t = Text {
        s: &datagram[..end],
        pos: 0,
    };
    let mut h = Header {
        frame: None,
        timestamp: -1.0,
        ts2: (0, 0, 0),
        has_bodycal: false,
    };
    let mut bodycal: Option<i32> = None;
    let (mut flysticks_old, mut tools) = (0i32, 0i32);
    if datagram.is_empty() {
        return Err(Malformed::Empty);
    }
    let mut known = true;
    let mut any_known = false;
    loop {
        if t.starts("fr ") {
            t.pos += 3;
            h.frame = Some(t.uint().ok_or(Malformed::Frame)?);
        } else if t.starts("ts ") {
            t.pos += 3;
            h.timestamp = t.double().ok_or(Malformed::Timestamp)?;
        } else if t.starts("ts2 ") {
            t.pos += 4;
            let sec = t.uint().ok_or(Malformed::Timestamp)?;
            let usec = t.uint().ok_or(Malformed::Timestamp)?;
            let lat = t.uint().ok_or(Malformed::Timestamp)?;
            h.ts2 = (sec, usec, lat);
        } else if t.starts("6dcal ") {
            t.pos += 6;
            h.has_bodycal = true;
            bodycal = Some(t.int().ok_or(Malformed::Calibrated)?);
        } else if t.starts("3d ") {
            t.pos += 3;
            markers(&mut t, targets)?;
        } else if t.starts("6d ") {
            t.pos += 3;
            bodies(&mut t, targets)?;
        } else if t.starts("6df ") {
            t.pos += 4;
            flysticks_old = flysticks_v1(&mut t, targets)?;
        } else if t.starts("6df2 ") {
            t.pos += 5;
            flysticks_v2(&mut t, targets)?;
        } else if t.starts("6dmt ") {
            t.pos += 5;
            tools = t.int().ok_or(Malformed::Tools)?;
        } else {
            known = false;
        }
        any_known |= known;
        known = true;
        if t.next_line().is_none() {
            break;
        }
    }
    if !any_known {
        return Err(Malformed::NoDTrackLine);
    }
    if let Some(n) = bodycal {
        targets.num_bodycal = n.wrapping_sub(flysticks_old).wrapping_sub(tools);
    }
    Ok(h)
}

fn markers(t: &mut Text<'_>, targets: &mut Targets) -> Result<(), Malformed> {
    targets.markers.clear();
    let n = count(t.int().ok_or(Malformed::Markers)?)?;
    for _ in 0..n {
        let mut b = t.block().ok_or(Malformed::Markers)?;
        let id = b.int().ok_or(Malformed::Markers)?;
        b.float().ok_or(Malformed::Markers)?;
        let mut b = t.block().ok_or(Malformed::Markers)?;
        let loc = b.floats::<3>().ok_or(Malformed::Markers)?;
        targets.markers.push(Marker { id, loc });
    }
    Ok(())
}

fn bodies(t: &mut Text<'_>, targets: &mut Targets) -> Result<(), Malformed> {
    for (i, b) in targets.bodies.iter_mut().enumerate() {
        *b = disabled_body(i);
    }
    let n = count(t.int().ok_or(Malformed::Bodies)?)?;
    for _ in 0..n {
        let mut b = t.block().ok_or(Malformed::Bodies)?;
        let id = b.int().ok_or(Malformed::Bodies)?;
        let quality = b.float().ok_or(Malformed::Bodies)?;
        if id < 0 {
            return Err(Malformed::Bodies);
        }
        let id = id as usize;
        if id >= MAX_TARGETS {
            return Err(Malformed::TooMany);
        }
        while targets.bodies.len() <= id {
            let next = targets.bodies.len();
            targets.bodies.push(disabled_body(next));
        }
        let loc = t
            .block()
            .and_then(|mut b| b.floats::<3>())
            .ok_or(Malformed::Bodies)?;
        let rot = t
            .block()
            .and_then(|mut b| b.floats::<9>())
            .ok_or(Malformed::Bodies)?;
        targets.bodies[id] = Body {
            id: id as i32,
            quality,
            loc,
            rot,
        };
    }
    Ok(())
}

/// Grows the Flystick list to `n` (new entries zeroed, as C++'s `resize`).
fn grow_flysticks(targets: &mut Targets, n: usize) {
    if n > targets.flysticks.len() {
        targets.flysticks.resize(n, Flystick::default());
    }
}

/// `6df`: returns the count (it is part of the `6dcal` total).
fn flysticks_v1(t: &mut Text<'_>, targets: &mut Targets) -> Result<i32, Malformed> {
    targets.old_flystick_format = true;
    let raw = t.int().ok_or(Malformed::Flysticks)?;
    let n = count(raw)?;
    grow_flysticks(targets, n);
    for i in 0..n {
        let mut b = t.block().ok_or(Malformed::Flysticks)?;
        let id = b.int().ok_or(Malformed::Flysticks)?;
        let quality = b.float().ok_or(Malformed::Flysticks)?;
        let bits = b.int().ok_or(Malformed::Flysticks)?;
        if id != i as i32 {
            return Err(Malformed::Flysticks);
        }
        let f = &mut targets.flysticks[i];
        f.id = id;
        f.quality = quality;
        f.num_button = 8;
        for (j, button) in f.button.iter_mut().take(8).enumerate() {
            *button = (bits >> j) & 1;
        }
        f.num_joystick = 2;
        f.joystick[0] = if bits & 0x20 != 0 {
            -1.0
        } else if bits & 0x80 != 0 {
            1.0
        } else {
            0.0
        };
        f.joystick[1] = if bits & 0x10 != 0 {
            -1.0
        } else if bits & 0x40 != 0 {
            1.0
        } else {
            0.0
        };
        f.loc = t
            .block()
            .and_then(|mut b| b.floats::<3>())
            .ok_or(Malformed::Flysticks)?;
        f.rot = t
            .block()
            .and_then(|mut b| b.floats::<9>())
            .ok_or(Malformed::Flysticks)?;
    }
    Ok(raw)
}

fn flysticks_v2(t: &mut Text<'_>, targets: &mut Targets) -> Result<(), Malformed> {
    targets.old_flystick_format = false;
    let calibrated = count(t.int().ok_or(Malformed::Flysticks)?)?;
    grow_flysticks(targets, calibrated);
    let n = count(t.int().ok_or(Malformed::Flysticks)?)?;
    // C++ writes past its array here; a frame naming more Flysticks than it has is damaged.
    if n > targets.flysticks.len() {
        return Err(Malformed::Flysticks);
    }
    for i in 0..n {
        let mut b = t.block().ok_or(Malformed::Flysticks)?;
        let id = b.int().ok_or(Malformed::Flysticks)?;
        let quality = b.float().ok_or(Malformed::Flysticks)?;
        let nb = b.int().ok_or(Malformed::Flysticks)?;
        let nj = b.int().ok_or(Malformed::Flysticks)?;
        if id != i as i32 || nb > MAX_FLYSTICK_BUTTONS as i32 || nj > MAX_FLYSTICK_JOYSTICK as i32 {
            return Err(Malformed::Flysticks);
        }
        let loc = t
            .block()
            .and_then(|mut b| b.floats::<3>())
            .ok_or(Malformed::Flysticks)?;
        let rot = t
            .block()
            .and_then(|mut b| b.floats::<9>())
            .ok_or(Malformed::Flysticks)?;
        let f = &mut targets.flysticks[i];
        f.id = id;
        f.quality = quality;
        f.num_button = nb;
        f.num_joystick = nj;
        f.loc = loc;
        f.rot = rot;
        // One int per 32 buttons (at most one, as there are at most 16), then the joystick.
        let mut b = t.block().ok_or(Malformed::Flysticks)?;
        let mut bits = 0;
        if nb > 0 {
            bits = b.int().ok_or(Malformed::Flysticks)?;
        }
        for j in 0..nj.max(0) as usize {
            f.joystick[j] = b.float().ok_or(Malformed::Flysticks)?;
        }
        for j in 0..nb.max(0) as usize {
            f.button[j] = bits & 1;
            bits >>= 1;
        }
    }
    Ok(())
}
