//! Sample age at transmission (R2P §3.4.5 synchronous HRT publishers, issue 14): for
//! every HRT message a module sends, the time from its publish (the `now` its node gave
//! `send`) to the start of frame of its first frame on the bus. With the publisher run
//! `lead` before its slot it is `lead` plus the slot's start-of-frame delay.
//!
//! How: the engine takes a topic's latched sample at the slot's `poll` and loads the
//! first frame into a mailbox in the same call; [`Tap`] sees the take (the block's
//! publish stamp, through `ModuleHost::published_at`), [`AgeMeter::after_poll`] pairs it
//! with the mailbox loaded meanwhile, and the mailbox's completion gives the SOF the bus
//! recorded (`SimController::tx_sof`). The SOF is global time, the stamp local: the
//! completion callback knows both clocks at one instant, and over an age below a
//! millisecond a 200 ppm clock moves the difference by < 0.2 µs. Frames before the
//! warm-up (`traffic::WARMUP_NS`, as the HRT misses) are not counted.
use rtcan_core::driver::{Event, Host, Token, TxOutcome, MAILBOXES};
use rtcan_core::{Frame, Nanos};
use rtcan_pubsub::ModuleHost;

use crate::controller::SimController;

/// Ages of one topic's HRT messages.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct AgeStat {
    /// Messages measured.
    pub count: u64,
    /// Largest age, ns.
    pub max_ns: Nanos,
    /// Sum of ages, ns (mean = sum / count).
    pub sum_ns: u64,
}

impl AgeStat {
    fn add(&mut self, age: Nanos) {
        self.count += 1;
        self.max_ns = self.max_ns.max(age);
        self.sum_ns = self.sum_ns.saturating_add(age);
    }

    /// Mean age, ns (0 before any).
    pub fn mean_ns(&self) -> f64 {
        if self.count == 0 {
            0.0
        } else {
            self.sum_ns as f64 / self.count as f64
        }
    }
}

/// The HRT samples the engine took during one call, in order: (tx index, publish stamp).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Taken {
    list: [Option<(u8, Nanos)>; MAILBOXES],
    n: usize,
}

impl Taken {
    /// The engine took `token` (topic `tx`) from `host`.
    pub fn note(&mut self, host: &ModuleHost<'_>, tx: u8, token: Token) {
        if let (Some(slot), Some(at)) = (self.list.get_mut(self.n), host.published_at(token)) {
            *slot = Some((tx, at));
            self.n += 1;
        }
    }
}

/// One HRT topic's sample ages as a module's report shows them.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct TopicAge {
    /// Topic name.
    pub topic: String,
    /// Its ages.
    pub stat: AgeStat,
}

/// Names `by_tx` (a module's ages per engine tx index) with `tx_names` (the module's
/// tx topics in table order, `plan.modules[m].tx`); topics never measured are left out.
pub fn named(by_tx: &[AgeStat], tx_names: &[String]) -> Vec<TopicAge> {
    by_tx
        .iter()
        .enumerate()
        .filter(|(_, s)| s.count > 0)
        .map(|(i, s)| TopicAge {
            topic: tx_names.get(i).cloned().unwrap_or_else(|| format!("tx{i}")),
            stat: *s,
        })
        .collect()
}

/// Every module's tx topic names in table order (for [`named`]).
pub fn tx_names(plan: &rtcan_model::Plan) -> Vec<Vec<String>> {
    plan.modules
        .iter()
        .map(|m| {
            m.tx.iter()
                .filter_map(|&t| plan.topics.get(t).map(|t| t.name.clone()))
                .collect()
        })
        .collect()
}

/// A `Host` in front of a `ModuleHost` that notes the HRT samples the engine takes.
pub struct Tap<'a, 'h> {
    host: &'a mut ModuleHost<'h>,
    /// What the engine took.
    pub taken: Taken,
}

impl<'a, 'h> Tap<'a, 'h> {
    /// A tap that has seen nothing.
    pub fn new(host: &'a mut ModuleHost<'h>) -> Self {
        Tap {
            host,
            taken: Taken::default(),
        }
    }
}

impl Host for Tap<'_, '_> {
    fn hrt_sample(&mut self, tx: u8) -> Option<Token> {
        let t = self.host.hrt_sample(tx)?;
        self.taken.note(self.host, tx, t);
        Some(t)
    }
    fn payload(&self, token: Token) -> &[u8] {
        self.host.payload(token)
    }
    fn tx_done(&mut self, tx: u8, token: Option<Token>, outcome: TxOutcome) {
        self.host.tx_done(tx, token, outcome);
    }
    fn deliver(&mut self, rx: u8, payload: &[u8], sof: Nanos) {
        self.host.deliver(rx, payload, sof);
    }
    fn event(&mut self, event: Event) {
        self.host.event(event);
    }
    fn module_state(&self) -> u8 {
        self.host.module_state()
    }
    fn service_rx(&mut self, frame: &Frame, sof: Nanos) {
        self.host.service_rx(frame, sof);
    }
    fn service_tx(&mut self) -> Option<Frame> {
        self.host.service_tx()
    }
    fn service_sent(&mut self) {
        self.host.service_sent();
    }
}

/// One module's sample-age meter, per topic (engine tx index).
#[derive(Clone, Debug, Default)]
pub struct AgeMeter {
    /// The HRT sample whose first frame each mailbox holds: (tx index, publish stamp).
    in_mailbox: [Option<(u8, Nanos)>; MAILBOXES],
    /// Ages per tx index.
    pub by_tx: Vec<AgeStat>,
    /// Samples taken whose mailbox could not be told (several loads in one poll).
    pub unpaired: u64,
}

impl AgeMeter {
    /// Which mailboxes are loaded (before an engine call).
    pub fn loaded(can: &SimController) -> [bool; MAILBOXES] {
        core::array::from_fn(|m| can.mailbox(m).is_some())
    }

    /// After an engine call through `tap`: pairs the samples it took with the
    /// mailboxes it loaded (in mailbox order; one take and one load is the slot path).
    pub fn after_poll(&mut self, before: [bool; MAILBOXES], taken: &Taken, can: &SimController) {
        if taken.n == 0 {
            return;
        }
        let fresh: Vec<usize> = (0..MAILBOXES)
            .filter(|&m| before.get(m) == Some(&false) && can.mailbox(m).is_some())
            .collect();
        if fresh.len() != taken.n {
            self.unpaired += taken.n as u64;
            return;
        }
        for (m, t) in fresh.into_iter().zip(taken.list.iter()) {
            if let Some(slot) = self.in_mailbox.get_mut(m) {
                *slot = *t;
            }
        }
    }

    /// Mailbox `mb` completed at local time `now` (before the engine hears of it): a
    /// successful first frame of an HRT sample gives its age.
    pub fn on_tx_done(&mut self, mb: usize, ok: bool, now: Nanos, can: &SimController) {
        let Some((tx, stamp)) = self.in_mailbox.get_mut(mb).and_then(Option::take) else {
            return;
        };
        let Some(sof) = can.tx_sof(mb) else { return };
        // After the warm-up, as the HRT misses (`run::window`): the first cycles after
        // sync carry samples published before the slot grid was known.
        if !ok || sof < crate::traffic::WARMUP_NS {
            return;
        }
        // Global SOF onto the local clock through this instant's pair of readings.
        let sof_local = i128::from(sof) - (i128::from(can.global_now()) - i128::from(now));
        let age = u64::try_from(sof_local - i128::from(stamp)).unwrap_or(0);
        let i = usize::from(tx);
        if self.by_tx.len() <= i {
            self.by_tx.resize(i + 1, AgeStat::default());
        }
        if let Some(s) = self.by_tx.get_mut(i) {
            s.add(age);
        }
    }

    /// Over every topic.
    pub fn total(&self) -> AgeStat {
        self.by_tx.iter().fold(AgeStat::default(), |a, s| AgeStat {
            count: a.count + s.count,
            max_ns: a.max_ns.max(s.max_ns),
            sum_ns: a.sum_ns.saturating_add(s.sum_ns),
        })
    }
}
