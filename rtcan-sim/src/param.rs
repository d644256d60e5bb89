//! Parameters over the bus in the triskar2 simulation (docs/SERVICES.md §2): every
//! module runs its parameter server (`rtcan_pubsub::param::bus::ParamServer` answering
//! with `rtcan_pubsub::param::serve`, persisted values in a `ParamStore` on its own F103
//! flash model), attached to its generated engine through `Host::service_rx`/`service_tx`
//! (`update::WithUpdate`); the host (`rtcan param`) asks through the gateway with a
//! `ParamClient`, one request after the other, each with a timeout. Requests and replies
//! are NRT frames of the reserved parameter channel (docs/PROTOCOL.md §2.3), so the
//! robot's HRT and SRT traffic is untouched.
//!
//! A request to the gateway itself never goes on the bus: the gateway answers it from
//! its own server (as a local service call).
use std::collections::VecDeque;

use rtcan_core::{Frame, Nanos};
use rtcan_model::params::{ParamDecl, ParamTy};
use rtcan_pubsub::flash::F103Flash;
use rtcan_pubsub::param::bus::{ClientEvent, ParamClient, ParamServer};
use rtcan_pubsub::param::{serve, ParamSpec, Reply, Request, Value};
use rtcan_pubsub::param_store::ParamStore;

/// Parameters a simulated module's store can hold.
pub const MAX_PARAMS: usize = 32;
/// The flash pages of a module's parameter store (two: one active, one to compact into).
pub type ParamFlash = F103Flash<2>;
type Store = ParamStore<ParamFlash, MAX_PARAMS>;

/// The value of `v` (robot.toml's f64) as a parameter of type `t`.
pub fn value(t: ParamTy, v: f64) -> Value {
    match t {
        ParamTy::F32 => Value::F32(v as f32),
        ParamTy::I32 => Value::I32(v as i32),
        ParamTy::U32 => Value::U32(v as u32),
        ParamTy::Bool => Value::Bool(v != 0.0),
    }
}

/// Per bus index, the module's parameters in wire-index order, as its firmware would
/// declare them (names and units stay on the host: the wire carries indices).
pub fn specs(decls: &[ParamDecl], modules: usize) -> Vec<Vec<ParamSpec>> {
    let mut out = vec![Vec::new(); modules];
    let mut sorted: Vec<&ParamDecl> = decls.iter().collect();
    sorted.sort_by_key(|p| (p.module, p.index));
    for p in sorted {
        if let Some(m) = out.get_mut(p.module) {
            m.push(ParamSpec {
                name: "",
                default: value(p.ty, p.default),
                min: value(p.ty, p.min),
                max: value(p.ty, p.max),
                unit: "",
                persist: p.persist,
            });
        }
    }
    out
}

/// What the host does in one run.
#[derive(Clone, Debug, PartialEq)]
pub struct ParamJob {
    /// Per bus index, the module's parameters (`specs`).
    pub specs: Vec<Vec<ParamSpec>>,
    /// The requests in order: (global time, bus index, request). Each is made once the
    /// previous one is answered or timed out, not before its time.
    pub requests: Vec<(Nanos, usize, Request)>,
    /// How long the host waits for each reply.
    pub timeout_ns: Nanos,
}

/// What became of one request.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ParamOutcome {
    pub module: usize,
    pub request: Request,
    /// Global time the host made the request, and the time of its reply (or of the
    /// timeout).
    pub asked_ns: Nanos,
    pub done_ns: Nanos,
    /// `None`: no reply within the timeout.
    pub reply: Option<Reply>,
}

/// A module's parameters and server.
struct ModuleParams {
    specs: Vec<ParamSpec>,
    values: Vec<u32>,
    refused: u32,
    server: ParamServer,
    store: Option<Store>,
    /// Persisted values loaded at the last power-on.
    loaded: usize,
}

impl ModuleParams {
    fn new(module: usize, specs: Vec<ParamSpec>, flash: ParamFlash) -> Self {
        let mut m = ModuleParams {
            values: specs.iter().map(|s| s.default.bits()).collect(),
            specs,
            refused: 0,
            server: ParamServer::new(module as u8),
            store: None,
            loaded: 0,
        };
        m.open(flash);
        m
    }

    /// Opens the store and takes its values, each range-checked again (as
    /// `Params::load`).
    fn open(&mut self, flash: ParamFlash) {
        let (store, _) = Store::open(flash);
        self.loaded = 0;
        for (i, bits) in store.values() {
            let i = usize::from(i);
            if let (Some(s), Some(v)) = (self.specs.get(i), self.values.get_mut(i)) {
                if s.persist && s.check(bits).is_ok() {
                    *v = bits;
                    self.loaded += 1;
                }
            }
        }
        self.store = Some(store);
    }

    /// Power on: RAM (values, server queue) gone, persisted values back from flash.
    fn power_on(&mut self, module: usize) {
        self.values = self.specs.iter().map(|s| s.default.bits()).collect();
        self.server = ParamServer::new(module as u8);
        if let Some(s) = self.store.take() {
            self.open(s.into_flash());
        }
    }

    fn serve(&mut self, request: &[u8]) -> Reply {
        let ModuleParams {
            specs,
            values,
            refused,
            store,
            ..
        } = self;
        serve_with(specs, values, refused, store, request)
    }

    fn rx(&mut self, frame: &Frame) -> bool {
        let ModuleParams {
            specs,
            values,
            refused,
            store,
            server,
            ..
        } = self;
        server.on_frame(frame, |r| serve_with(specs, values, refused, store, r))
    }
}

/// The module's `serve`, persisting through its store (a failed flash write is the
/// `NotPersisted` reply).
fn serve_with(
    specs: &[ParamSpec],
    values: &mut [u32],
    refused: &mut u32,
    store: &mut Option<Store>,
    request: &[u8],
) -> Reply {
    serve(specs, values, refused, request, &mut |i, b| {
        store.as_mut().is_some_and(|s| s.write(i, b).is_ok())
    })
}

/// Which channel's frame a module's engine holds (the engine asks for one host frame
/// at a time and reports it sent: the wrapper must know whose it was).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Channel {
    Params,
    Update,
}

/// The host's side: the client and the requests still to make.
struct HostParams {
    client: ParamClient,
    pending: VecDeque<(Nanos, usize, Request)>,
    /// The request in flight: module, request, asked at.
    current: Option<(usize, Request, Nanos)>,
    results: Vec<ParamOutcome>,
}

/// Everything parameters add to one simulation.
pub struct ParamBus {
    host: HostParams,
    modules: Vec<ModuleParams>,
    /// Per bus index, the channel of the host frame its engine holds.
    pub offered: Vec<Option<Channel>>,
}

/// What the parameters did in a run.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ParamLog {
    /// Every request in order (unfinished ones at the end of the run are missing).
    pub results: Vec<ParamOutcome>,
    /// Per bus index, the live values at the end of the run (wire bits, index order).
    pub values: Vec<Vec<u32>>,
    /// Per bus index, values refused by the module.
    pub refused: Vec<u32>,
    /// Per bus index, requests the module's server answered.
    pub served: Vec<u32>,
    /// Per bus index, persisted values loaded at its last power-on.
    pub loaded: Vec<usize>,
}

impl ParamBus {
    /// The job's modules with empty flash (first start: defaults).
    pub fn new(job: &ParamJob, modules: usize) -> Self {
        Self::with_flash(job, modules, Vec::new())
    }

    /// The job's modules, with the parameter flash of some of them (bus index → pages,
    /// as a previous run left it).
    pub fn with_flash(job: &ParamJob, modules: usize, flash: Vec<(usize, ParamFlash)>) -> Self {
        let mods = (0..modules)
            .map(|m| {
                let f = flash
                    .iter()
                    .find(|(i, _)| *i == m)
                    .map_or_else(ParamFlash::new, |(_, f)| f.clone());
                ModuleParams::new(m, job.specs.get(m).cloned().unwrap_or_default(), f)
            })
            .collect();
        ParamBus {
            host: HostParams {
                client: ParamClient::new(job.timeout_ns),
                pending: job.requests.iter().copied().collect(),
                current: None,
                results: Vec::new(),
            },
            modules: mods,
            offered: vec![None; modules],
        }
    }

    /// Module `m` was powered on again.
    pub fn power_on(&mut self, m: usize) {
        if let Some(p) = self.modules.get_mut(m) {
            p.power_on(m);
        }
        if let Some(o) = self.offered.get_mut(m) {
            *o = None;
        }
    }

    /// The host at global time `g`: a timeout, the next request.
    fn host_poll(&mut self, g: Nanos) {
        let deadline = self.host.client.deadline();
        if let Some(ClientEvent::TimedOut { .. }) = self.host.client.poll(g) {
            if let Some((module, request, asked)) = self.host.current.take() {
                self.host.results.push(ParamOutcome {
                    module,
                    request,
                    asked_ns: asked,
                    done_ns: deadline.unwrap_or(g),
                    reply: None,
                });
            }
        }
        while self.host.current.is_none() {
            let Some(&(at, module, request)) = self.host.pending.front() else {
                return;
            };
            if g < at {
                return;
            }
            self.host.pending.pop_front();
            let done = |reply: Option<Reply>| ParamOutcome {
                module,
                request,
                asked_ns: g,
                done_ns: g,
                reply,
            };
            if module == 0 {
                // The gateway's own parameters: served in place, never on the bus.
                let reply = self.modules.first_mut().map(|p| p.serve(&request.encode()));
                self.host.results.push(done(reply));
                continue;
            }
            match self.host.client.request(module as u8, request, g) {
                Ok(()) => self.host.current = Some((module, request, g)),
                // No such module on the channel: nobody can answer.
                Err(_) => self.host.results.push(done(None)),
            }
        }
    }

    /// A frame of the host range at module `m`, global time `g`; whether it was a
    /// parameter frame.
    pub fn rx(&mut self, m: usize, frame: &Frame, g: Nanos) -> bool {
        if m == 0 {
            let ev = self.host.client.on_frame(frame, g);
            if let Some(ClientEvent::Reply { reply, .. }) = ev {
                if let Some((module, request, asked)) = self.host.current.take() {
                    self.host.results.push(ParamOutcome {
                        module,
                        request,
                        asked_ns: asked,
                        done_ns: g,
                        reply: Some(reply),
                    });
                }
            }
            self.host_poll(g);
            return rtcan_pubsub::param::bus::parse_reply(frame).is_some();
        }
        self.modules.get_mut(m).is_some_and(|p| p.rx(frame))
    }

    /// The parameter frame module `m` would send now.
    pub fn tx(&mut self, m: usize, g: Nanos) -> Option<Frame> {
        if m == 0 {
            self.host_poll(g);
            return self.host.client.next_frame();
        }
        self.modules.get(m)?.server.next()
    }

    /// Module `m`'s parameter frame was sent.
    pub fn sent(&mut self, m: usize) {
        if m == 0 {
            self.host.client.sent();
        } else if let Some(p) = self.modules.get_mut(m) {
            p.server.sent();
        }
    }

    /// The requests made so far and their outcomes.
    pub fn results(&self) -> &[ParamOutcome] {
        &self.host.results
    }

    /// Module `m`'s parameter flash (to carry into another run: a reset robot).
    pub fn flash(&self, m: usize) -> Option<ParamFlash> {
        Some(self.modules.get(m)?.store.as_ref()?.flash().clone())
    }

    /// The run's log.
    pub fn log(&self) -> ParamLog {
        ParamLog {
            results: self.host.results.clone(),
            values: self.modules.iter().map(|p| p.values.clone()).collect(),
            refused: self.modules.iter().map(|p| p.refused).collect(),
            served: self
                .modules
                .iter()
                .map(|p| p.server.stats.requests)
                .collect(),
            loaded: self.modules.iter().map(|p| p.loaded).collect(),
        }
    }
}
