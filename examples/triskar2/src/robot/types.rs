//! Robot message types of robot.toml (`[types.*]`): fixed-size, little-endian, fields
//! packed in declaration order. Stand-in for the structs rtcan-codegen emits; the byte
//! layout is the one robot.toml specifies, so these interoperate with generated code.
use rtcan_pubsub::Message;

/// Little-endian field writer over a wire buffer (never panics on a short buffer).
struct Put<'a>(&'a mut [u8], usize);

impl Put<'_> {
    fn bytes<const L: usize>(&mut self, b: [u8; L]) -> &mut Self {
        if let Some(o) = self.0.get_mut(self.1..self.1 + L) {
            o.copy_from_slice(&b);
        }
        self.1 += L;
        self
    }
}

/// Little-endian field reader.
struct Get<'a>(&'a [u8]);

impl Get<'_> {
    fn bytes<const L: usize>(&mut self) -> Option<[u8; L]> {
        let (head, rest) = self.0.split_first_chunk::<L>()?;
        self.0 = rest;
        Some(*head)
    }
    fn f32(&mut self) -> Option<f32> {
        self.bytes().map(f32::from_le_bytes)
    }
}

macro_rules! message {
    ($t:ident, $size:literal, |$s:ident, $p:ident| $enc:block, |$g:ident| $dec:expr) => {
        impl Message for $t {
            const SIZE: usize = $size;
            type Wire = [u8; $size];
            fn encode(&self, out: &mut [u8]) {
                let $s = self;
                let $p = &mut Put(out, 0);
                $enc
            }
            fn decode(bytes: &[u8]) -> Option<Self> {
                if bytes.len() != $size {
                    return None;
                }
                let $g = &mut Get(bytes);
                $dec
            }
        }
    };
}

/// `[types.Twist]`: velocity command, m/s and rad/s.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Twist {
    pub vx: f32,
    pub vy: f32,
    pub wz: f32,
}
message!(Twist, 12, |s, p| {
    p.bytes(s.vx.to_le_bytes()).bytes(s.vy.to_le_bytes()).bytes(s.wz.to_le_bytes());
}, |g| Some(Twist { vx: g.f32()?, vy: g.f32()?, wz: g.f32()? }));

/// `[types.WheelSpeeds]`: wheel speed set points, rad/s.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct WheelSpeeds {
    pub w: [f32; 3],
}
message!(WheelSpeeds, 12, |s, p| {
    for w in s.w {
        p.bytes(w.to_le_bytes());
    }
}, |g| Some(WheelSpeeds { w: [g.f32()?, g.f32()?, g.f32()?] }));

/// `[types.Encoder]`: one motor's encoder.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Encoder {
    pub ticks: i32,
    pub speed: f32,
}
message!(Encoder, 8, |s, p| {
    p.bytes(s.ticks.to_le_bytes()).bytes(s.speed.to_le_bytes());
}, |g| Some(Encoder { ticks: i32::from_le_bytes(g.bytes()?), speed: g.f32()? }));

/// `[types.Odometry]`: pose and velocity in the odometry frame.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Odometry {
    pub x: f32,
    pub y: f32,
    pub theta: f32,
    pub vx: f32,
    pub vy: f32,
    pub wz: f32,
}
message!(Odometry, 24, |s, p| {
    for v in [s.x, s.y, s.theta, s.vx, s.vy, s.wz] {
        p.bytes(v.to_le_bytes());
    }
}, |g| Some(Odometry {
    x: g.f32()?,
    y: g.f32()?,
    theta: g.f32()?,
    vx: g.f32()?,
    vy: g.f32()?,
    wz: g.f32()?,
}));

/// `[types.Proximity]`: four IR rangers, mm.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Proximity {
    pub range_mm: [u16; 4],
}
message!(Proximity, 8, |s, p| {
    for r in s.range_mm {
        p.bytes(r.to_le_bytes());
    }
}, |g| {
    let mut range_mm = [0u16; 4];
    for r in range_mm.iter_mut() {
        *r = u16::from_le_bytes(g.bytes()?);
    }
    Some(Proximity { range_mm })
});

/// `[types.Battery]`: PSU monitor.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Battery {
    pub mv: u16,
    pub ma: i16,
    pub pct: u8,
}
message!(Battery, 5, |s, p| {
    p.bytes(s.mv.to_le_bytes()).bytes(s.ma.to_le_bytes()).bytes([s.pct]);
}, |g| Some(Battery {
    mv: u16::from_le_bytes(g.bytes()?),
    ma: i16::from_le_bytes(g.bytes()?),
    pct: g.bytes::<1>()?[0],
}));

/// `[types.LogLine]`: short text log.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LogLine {
    pub level: u8,
    pub code: u16,
    pub text: [u8; 29],
}
message!(LogLine, 32, |s, p| {
    p.bytes([s.level]).bytes(s.code.to_le_bytes()).bytes(s.text);
}, |g| Some(LogLine {
    level: g.bytes::<1>()?[0],
    code: u16::from_le_bytes(g.bytes()?),
    text: g.bytes()?,
}));
