//! Firmware update over the bus in the triskar2 simulation (docs/SERVICES.md §4): the
//! host's `Sender` behind the gateway (host → gateway link → bus), each target module's
//! `Port` on its own F103 flash model, both attached to their module's generated engine
//! through `Host::service_rx`/`service_tx` (the engine sends the frames as NRT in free
//! windows, `rtcan_core::service`). The robot's HRT and SRT traffic keeps running.
//!
//! Flash takes time: a module's reply leaves once the flash operations of its request
//! are over, at the F103's worst-case datasheet figures (`ERASE_NS` per page,
//! `PROGRAM_NS` per half-word). The gateway link (USART 115 200 Bd, `triskar2-link`
//! framing) carries each request to the gateway before its first frame can go on the
//! bus: `LINK_NS` per request, one request after the other, not overlapped with the bus
//! (conservative: a gateway buffering requests would overlap them). The replies' way
//! back over the link (13 bytes, 1.1 ms) is not modelled.
use std::collections::VecDeque;

use rtcan_boot::can::Port;
use rtcan_boot::sender::{Config, Outcome, Sender};
use rtcan_boot::update::messages;
use rtcan_boot::{Crc32, Layout};
use rtcan_core::driver::{Event, Host, Token, TxOutcome};
use rtcan_core::{Frame, Nanos};
use rtcan_pubsub::flash::F103Flash;
use rtcan_pubsub::ModuleHost;

/// The slots as the bootloader sees them (`rtcan-boot/bootloader`): two slots of 30
/// 1 KiB pages (header page + 29 KiB image) after the bootloader's 8 KiB; the
/// generated `FINGERPRINT` at image offset 0x1D0.
pub const LAYOUT: Layout = Layout {
    slot_page: [0, 30],
    slot_pages: 30,
    fingerprint_offset: 0x1D0,
};
/// The slot region the model covers.
pub type SlotFlash = F103Flash<60>;

/// F103 page erase, worst case (datasheet t_ERASE 40 ms).
pub const ERASE_NS: Nanos = 40_000_000;
/// F103 half-word program, worst case (datasheet t_PROG 70 µs).
pub const PROGRAM_NS: Nanos = 70_000;

/// One request over the gateway link: `COBS(topic, 256-byte payload, CRC-16)` and the
/// 0x00 delimiter = 1 + 256 + 2 + 2 COBS code bytes + 1 = 262 bytes of 10 bits (8N1)
/// at 115 200 Bd.
pub const LINK_NS: Nanos = 262 * 10 * 1_000_000_000 / 115_200;

/// A deterministic test image of `len` bytes for the robot of `fingerprint` (the
/// fingerprint at `LAYOUT.fingerprint_offset`, as the linker places it).
pub fn test_image(len: usize, fingerprint: u32, salt: u8) -> Vec<u8> {
    let mut v: Vec<u8> = (0..len)
        .map(|i| ((i as u32).wrapping_mul(2_654_435_761) >> 24) as u8 ^ salt)
        .collect();
    let o = LAYOUT.fingerprint_offset as usize;
    if let Some(d) = v.get_mut(o..o + 4) {
        d.copy_from_slice(&fingerprint.to_le_bytes());
    }
    v
}

/// A module's slots with `image` committed in slot 0, as after factory flashing.
pub fn flashed(image: &[u8], fingerprint: u32) -> Box<SlotFlash> {
    let mut f = Box::new(SlotFlash::new());
    let mut rx = rtcan_boot::update::Receiver::new(&LAYOUT, None);
    let mut buf = [0u8; 300];
    for (m, _) in messages(image, fingerprint, rtcan_boot::update::MAX_CHUNK) {
        if let Some(n) = m.encode(&mut buf) {
            rx.handle(&mut *f, buf.get(..n).unwrap_or(&[]));
        }
    }
    f
}

/// A power cut to inject: while handling request `request` (0 = the first) of the
/// update, after `op` more flash operations; the module is then down for `down_ns`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Cut {
    pub request: u32,
    pub op: u32,
    pub down_ns: Nanos,
}

/// One module to update.
#[derive(Clone, Debug, PartialEq)]
pub struct Target {
    /// Bus index.
    pub module: usize,
    pub image: Vec<u8>,
    /// The fingerprint announced in `Begin` (the robot's, normally).
    pub fingerprint: u32,
}

/// What the host does: the targets in order, from `start_ns`.
#[derive(Clone, Debug, PartialEq)]
pub struct UpdateJob {
    pub targets: Vec<Target>,
    pub start_ns: Nanos,
    pub config: Config,
    /// Flash of every module before the run (bus index → slots); modules not listed
    /// start with `flashed(test_image(4096, fingerprint, 0))`.
    pub flash: Vec<(usize, Box<SlotFlash>)>,
    pub cut: Option<(usize, Cut)>,
}

/// How one module's update went.
#[derive(Clone, Debug, PartialEq)]
pub struct UpdateResult {
    pub module: usize,
    pub bytes: usize,
    /// Request frames the host sent (through the gateway).
    pub frames: u32,
    pub retries: u32,
    /// Bus time from the first request frame to the last reply, ns.
    pub bus_time_ns: Nanos,
    pub outcome: Option<Outcome>,
}

/// A target module's side.
pub struct ModuleSide {
    pub flash: Box<SlotFlash>,
    port: Port<'static>,
    /// Global times at which the queued replies may leave (flash work done).
    ready: VecDeque<Nanos>,
    busy_until: Nanos,
    /// Requests handled since power-on of this update (for `Cut`).
    requests: u32,
    cut: Option<Cut>,
    /// Power cuts that hit (global time).
    pub cuts: Vec<Nanos>,
    /// What the bootloader booted at each power-on after a cut: (slot, CRC-32).
    pub boots: Vec<Option<(usize, u32)>>,
}

impl ModuleSide {
    fn new(module: usize, flash: Box<SlotFlash>, fingerprint: u32, cut: Option<Cut>) -> Self {
        let running = LAYOUT.boot_slot(&*flash, Some(fingerprint));
        ModuleSide {
            port: Port::new(module as u8, &LAYOUT, running).with_fingerprint(fingerprint),
            flash,
            ready: VecDeque::new(),
            busy_until: 0,
            requests: 0,
            cut,
            cuts: Vec::new(),
            boots: Vec::new(),
        }
    }

    /// The slot the bootloader would boot now.
    pub fn boot_slot(&self, fingerprint: u32) -> Option<usize> {
        LAYOUT.boot_slot(&*self.flash, Some(fingerprint))
    }

    /// Power on: RAM state gone, the bootloader picks the slot from flash.
    fn power_on(&mut self, module: usize, fingerprint: u32) {
        let slot = self.boot_slot(fingerprint);
        self.port = Port::new(module as u8, &LAYOUT, slot).with_fingerprint(fingerprint);
        self.ready.clear();
        self.busy_until = 0;
        let crc = slot.and_then(|s| LAYOUT.header(&*self.flash, s).map(|h| (s, h.crc)));
        self.boots.push(crc);
    }

    /// A frame of the update range at global time `g`; `Some(down_ns)` if a power
    /// cut hit while handling it.
    fn rx(&mut self, frame: &Frame, g: Nanos) -> Option<Nanos> {
        let ops0 = self.flash.ops;
        let erases0: u32 = self.flash.erases.iter().sum();
        let cut = self.cut.filter(|c| c.request == self.requests);
        if let Some(c) = cut {
            self.flash.cut_after = Some(c.op);
        }
        let reply = self.port.on_frame(&mut *self.flash, frame, g)?;
        self.requests += 1;
        if let Some(c) = cut {
            let hit = self.flash.cut_after == Some(0);
            self.flash.cut_after = None;
            if hit {
                self.cut = None;
                self.cuts.push(g);
                return Some(c.down_ns);
            }
        }
        let erases = self.flash.erases.iter().sum::<u32>() - erases0;
        let programs = (self.flash.ops - ops0).saturating_sub(erases);
        let work = Nanos::from(erases) * ERASE_NS + Nanos::from(programs) * PROGRAM_NS;
        self.busy_until = self.busy_until.max(g) + work;
        self.ready.push_back(self.busy_until);
        let _ = reply;
        None
    }

    fn tx(&self, g: Nanos) -> Option<Frame> {
        self.ready.front().filter(|&&at| at <= g)?;
        self.port.next()
    }

    fn sent(&mut self) {
        self.ready.pop_front();
        self.port.sent();
    }
}

/// A module's power cuts (global times) and what booted after each power-on (slot,
/// CRC-32; `None`: nothing valid).
pub type CutLog = (Vec<Nanos>, Vec<Option<(usize, u32)>>);

/// The update in progress: module, image bytes, sender, time of its first frame and of
/// its last reply.
type Current = (usize, usize, Sender<Vec<u8>>, Option<Nanos>, Nanos);

/// The host behind the gateway.
pub struct HostSide {
    pending: VecDeque<Target>,
    current: Option<Current>,
    config: Config,
    start_ns: Nanos,
    /// When the request being sent reached the gateway over the link, and when the
    /// link is free again.
    link_at: Option<Nanos>,
    link_free: Nanos,
    pub results: Vec<UpdateResult>,
    /// The gateway relays a real host's frames instead (`UpdateBus::relay`).
    relay: Option<Relay>,
}

/// The gateway's side of a real host link (`rtcan flash --serial`): the host channels'
/// frames from the host, queued for the bus in order; the frames the bus brought back.
#[derive(Clone, Debug, Default)]
struct Relay {
    to_bus: VecDeque<Frame>,
    from_bus: Vec<Frame>,
}

impl HostSide {
    fn poll(&mut self, g: Nanos) {
        if g < self.start_ns {
            return;
        }
        if let Some((m, bytes, s, first, last)) = &self.current {
            if let Some(o) = s.outcome() {
                self.results.push(UpdateResult {
                    module: *m,
                    bytes: *bytes,
                    frames: s.stats.frames,
                    retries: s.stats.retries,
                    bus_time_ns: first.map_or(0, |f| last.saturating_sub(f)),
                    outcome: Some(o),
                });
                self.current = None;
            }
        }
        if self.current.is_none() {
            if let Some(t) = self.pending.pop_front() {
                let bytes = t.image.len();
                let s = Sender::new(t.module as u8, t.image, t.fingerprint, self.config);
                self.current = Some((t.module, bytes, s, None, g));
            }
        }
    }

    /// Targets not finished by the end of the run.
    pub fn unfinished(&self) -> Vec<UpdateResult> {
        let cur = self
            .current
            .iter()
            .map(|(m, bytes, s, first, last)| UpdateResult {
                module: *m,
                bytes: *bytes,
                frames: s.stats.frames,
                retries: s.stats.retries,
                bus_time_ns: first.map_or(0, |f| last.saturating_sub(f)),
                outcome: None,
            });
        let rest = self.pending.iter().map(|t| UpdateResult {
            module: t.module,
            bytes: t.image.len(),
            frames: 0,
            retries: 0,
            bus_time_ns: 0,
            outcome: None,
        });
        cur.chain(rest).collect()
    }
}

/// Everything the update adds to one simulation.
pub struct UpdateBus {
    pub host: HostSide,
    /// Per bus index: the module side (the gateway has none: it is updated over its
    /// host link, not the bus).
    pub modules: Vec<Option<ModuleSide>>,
    pub fingerprint: u32,
}

impl UpdateBus {
    pub fn new(job: &UpdateJob, modules: usize, fingerprint: u32) -> Self {
        let mut flash: Vec<Option<Box<SlotFlash>>> = (0..modules).map(|_| None).collect();
        for (m, f) in &job.flash {
            if let Some(x) = flash.get_mut(*m) {
                *x = Some(f.clone());
            }
        }
        let sides = flash
            .into_iter()
            .enumerate()
            .map(|(m, f)| {
                (m != 0).then(|| {
                    let f = f
                        .unwrap_or_else(|| flashed(&test_image(4096, fingerprint, 0), fingerprint));
                    let cut = job.cut.filter(|c| c.0 == m).map(|c| c.1);
                    ModuleSide::new(m, f, fingerprint, cut)
                })
            })
            .collect();
        UpdateBus {
            host: HostSide {
                pending: job.targets.iter().cloned().collect(),
                current: None,
                config: job.config,
                start_ns: job.start_ns,
                link_at: None,
                link_free: 0,
                results: Vec::new(),
                relay: None,
            },
            modules: sides,
            fingerprint,
        }
    }

    /// Every module (not the gateway) with its update port on factory-flashed slots, and
    /// the gateway relaying a real host's frames (`relay_to_bus`, `relay_from_bus`)
    /// instead of running a sender.
    pub fn relay(modules: usize, fingerprint: u32) -> Self {
        let job = UpdateJob {
            targets: Vec::new(),
            start_ns: 0,
            config: Config::default(),
            flash: Vec::new(),
            cut: None,
        };
        let mut u = UpdateBus::new(&job, modules, fingerprint);
        u.host.relay = Some(Relay::default());
        u
    }

    /// A frame from the host for the bus: queued if it is an NRT frame of the host
    /// channels (`rtcan_core::service::sendable`), else refused (`false`): the link must
    /// not let a host put a topic's or the sync's identifier on the bus.
    pub fn relay_to_bus(&mut self, frame: Frame) -> bool {
        match &mut self.host.relay {
            Some(r) if rtcan_core::service::sendable(&frame) => {
                r.to_bus.push_back(frame);
                true
            }
            _ => false,
        }
    }

    /// The host channels' frames the gateway received since the last call.
    pub fn relay_from_bus(&mut self) -> Vec<Frame> {
        self.host
            .relay
            .as_mut()
            .map(|r| std::mem::take(&mut r.from_bus))
            .unwrap_or_default()
    }

    /// Module `m` was powered on again.
    pub fn power_on(&mut self, m: usize) {
        let fp = self.fingerprint;
        if let Some(Some(side)) = self.modules.get_mut(m) {
            side.power_on(m, fp);
        }
    }

    /// Every result, finished or not, in target order.
    pub fn results(&self) -> Vec<UpdateResult> {
        let mut r = self.host.results.clone();
        r.extend(self.host.unfinished());
        r
    }

    /// Module `m`'s power cuts (global times) and what it booted after each power-on.
    pub fn cuts(&self, m: usize) -> CutLog {
        match self.modules.get(m) {
            Some(Some(s)) => (s.cuts.clone(), s.boots.clone()),
            _ => (Vec::new(), Vec::new()),
        }
    }

    /// The CRC-32 of what module `m` would boot (slot, length, CRC), if anything.
    pub fn booted(&self, m: usize) -> Option<(usize, u32, u32)> {
        let side = self.modules.get(m)?.as_ref()?;
        let s = side.boot_slot(self.fingerprint)?;
        let h = LAYOUT.header(&*side.flash, s)?;
        Some((s, h.len, h.crc))
    }
}

/// The generated `ModuleHost` plus this module's side of the host channels — the
/// update channel and the parameter channel (`param.rs`) — as the engine's `Host`.
pub(crate) struct WithUpdate<'a> {
    pub host: &'a mut ModuleHost<'static>,
    pub bus: Option<&'a mut UpdateBus>,
    pub params: Option<&'a mut crate::param::ParamBus>,
    pub module: usize,
    /// Global time of the engine call.
    pub now: Nanos,
    /// A power cut hit this module: down for this long from `now`.
    pub cut: Option<Nanos>,
    /// HRT samples the engine took in this call (sample age at transmission).
    pub taken: crate::sample_age::Taken,
}

impl WithUpdate<'_> {
    fn update_rx(&mut self, frame: &Frame) {
        let Some(bus) = self.bus.as_deref_mut() else {
            return;
        };
        let g = self.now;
        if self.module == 0 {
            if let Some(r) = &mut bus.host.relay {
                r.from_bus.push(*frame);
                return;
            }
            if let Some((_, _, s, _, last)) = &mut bus.host.current {
                s.on_frame(frame, g);
                *last = g;
            }
            bus.host.poll(g);
        } else if let Some(Some(side)) = bus.modules.get_mut(self.module) {
            self.cut = self.cut.or(side.rx(frame, g));
        }
    }

    fn update_tx(&mut self) -> Option<Frame> {
        let bus = self.bus.as_deref_mut()?;
        let g = self.now;
        if self.module == 0 {
            let h = &mut bus.host;
            if let Some(r) = &h.relay {
                return r.to_bus.front().copied();
            }
            h.poll(g);
            let (_, _, s, _, _) = h.current.as_mut()?;
            let f = s.next_frame(g)?;
            // A request's frames leave once the whole request came over the link.
            let at = match h.link_at {
                Some(at) => at,
                None => {
                    let at = h.link_free.max(g) + LINK_NS;
                    h.link_at = Some(at);
                    h.link_free = at;
                    at
                }
            };
            (g >= at).then_some(f)
        } else {
            bus.modules.get(self.module)?.as_ref()?.tx(g)
        }
    }

    fn update_sent(&mut self) {
        let Some(bus) = self.bus.as_deref_mut() else {
            return;
        };
        let g = self.now;
        if self.module == 0 {
            if let Some(r) = &mut bus.host.relay {
                r.to_bus.pop_front();
                return;
            }
            if let Some((_, _, s, first, _)) = &mut bus.host.current {
                s.sent(g);
                first.get_or_insert(g);
                // Every request is `REQUEST_FRAMES` frames: the next one needs the link.
                if s.stats.frames % u32::from(rtcan_boot::can::REQUEST_FRAMES) == 0 {
                    bus.host.link_at = None;
                }
            }
        } else if let Some(Some(side)) = bus.modules.get_mut(self.module) {
            side.sent();
        }
    }
}

impl Host for WithUpdate<'_> {
    fn hrt_sample(&mut self, tx: u8) -> Option<Token> {
        let t = self.host.hrt_sample(tx)?;
        self.taken.note(self.host, tx, t);
        Some(t)
    }
    fn payload(&self, token: Token) -> &[u8] {
        self.host.payload(token)
    }
    fn tx_done(&mut self, tx: u8, token: Option<Token>, outcome: TxOutcome) {
        self.host.tx_done(tx, token, outcome)
    }
    fn deliver(&mut self, rx: u8, payload: &[u8], sof: Nanos) {
        self.host.deliver(rx, payload, sof)
    }
    fn event(&mut self, event: Event) {
        self.host.event(event)
    }
    fn module_state(&self) -> u8 {
        self.host.module_state()
    }
    fn service_rx(&mut self, frame: &Frame, _sof: Nanos) {
        let (m, g) = (self.module, self.now);
        if let Some(p) = self.params.as_deref_mut() {
            if p.rx(m, frame, g) {
                return;
            }
        }
        self.update_rx(frame);
    }
    fn service_tx(&mut self) -> Option<Frame> {
        let (m, g) = (self.module, self.now);
        let Some(p) = self.params.as_deref_mut() else {
            return self.update_tx();
        };
        // The engine holds one host frame at a time, offered unchanged until sent: once
        // a channel's frame is offered, that channel keeps the turn until
        // `service_sent`. Parameters first (a short request overtakes a long update in
        // progress).
        let offered = p.offered.get(m).copied().flatten();
        match offered {
            Some(crate::param::Channel::Params) => return p.tx(m, g),
            Some(crate::param::Channel::Update) => return self.update_tx(),
            None => {}
        }
        if let Some(f) = p.tx(m, g) {
            if let Some(o) = p.offered.get_mut(m) {
                *o = Some(crate::param::Channel::Params);
            }
            return Some(f);
        }
        let u = self.update_tx();
        if u.is_some() {
            if let Some(o) = self
                .params
                .as_deref_mut()
                .and_then(|p| p.offered.get_mut(m))
            {
                *o = Some(crate::param::Channel::Update);
            }
        }
        u
    }
    fn service_sent(&mut self) {
        let m = self.module;
        let Some(p) = self.params.as_deref_mut() else {
            return self.update_sent();
        };
        match p.offered.get_mut(m).and_then(Option::take) {
            Some(crate::param::Channel::Params) => p.sent(m),
            Some(crate::param::Channel::Update) => self.update_sent(),
            // Nothing offered: nothing to account.
            None => {}
        }
    }
}

/// CRC-32 of an image (what `rtcan flash` prints).
pub fn crc(image: &[u8]) -> u32 {
    Crc32::of(image)
}
