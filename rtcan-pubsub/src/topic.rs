//! A topic: the message pool, the subscriber queues and the remote (bus) side.
//!
//! Memory layout (decided here, see README): every pool block holds the typed value
//! `T` (local subscribers read it in place through a refcounted handle: zero copy) and
//! its wire encoding `T::Wire` (written once at publish, only when the topic is sent
//! on the bus, so the engine reads `payload(token)` in place: zero copy to the CAN
//! controller). Local-only topics pay `T::SIZE` unused bytes per block.
//!
//! Concurrency: block ownership is tracked by refcounts inside one
//! `critical_section::Mutex`. A block's value is written only while its single owner
//! (the publisher's `Loan`) holds it, and read only while a handle holds a reference,
//! so the `UnsafeCell` contents are never written and read at the same time.
//!
//! Wake-ups: a waker is never called inside the critical section. Code inside it only
//! marks the waker due; `Topic::with` sees the mark as the section ends, takes the due
//! wakers out (in a section of their own) and calls them after it, so a `wake()` that
//! runs its task at once (and publishes, receives or drops a handle on this very topic)
//! finds the state free.
//!
//! Flash: a topic is two statics. [`TopicCells`] holds every mutable byte and its
//! initial value is all zeros (pool `used` mask, `Option` indices, `None` wakers), so it
//! lands in .bss and costs no flash; a non-zero byte would move the whole static to
//! .data, stored twice (RAM and its flash copy). [`Topic`] holds the immutable
//! configuration (`Remote`, `kick`) and a reference to its cells: it has no interior
//! mutability, so it stays in .rodata (12 bytes).
use core::cell::{RefCell, UnsafeCell};
use core::mem::MaybeUninit;
use core::task::Waker;

use critical_section::Mutex;
use rtcan_core::driver::{Token, TxOutcome};
use rtcan_core::time::Nanos;

use crate::message::{Message, WireBuf};
use crate::ring::Ring;

/// How a topic leaves this module (from robot.toml: is there a subscriber on another
/// module, and which class the topic has on the bus).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Remote {
    /// Local subscribers only.
    None,
    /// Sampled at this module's reserved slots: the latest value is latched.
    Hrt,
    /// Sent by deadline (EDF): queued for the engine, misses are reported; `publish`
    /// refuses (the caller is told) while the queue towards the engine is full.
    Srt,
    /// Best effort with back-pressure: `publish` refuses while the engine queue is full.
    Nrt,
}

/// Counters of one topic (saturating). Nothing is dropped without being counted.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct TopicStats {
    /// Messages published (locally or received from the bus); wraps.
    pub published: u32,
    /// `alloc` found no free block.
    pub pool_exhausted: u32,
    /// SRT publishes refused because the queue towards the engine was full (the
    /// publisher got `SendError::QueueFull` / the loan back).
    pub remote_overflows: u32,
    /// HRT values replaced by a newer one before their slot came.
    pub hrt_replaced: u32,
    /// HRT slots that found nothing to send.
    pub nothing_to_send: u32,
    /// Messages the engine reported sent.
    pub sent: u32,
    /// Messages the engine dropped at their deadline.
    pub deadline_misses: u32,
    /// Messages the engine refused as not submittable (configuration mismatch).
    pub not_submittable: u32,
    /// Bus payloads that failed to decode.
    pub rx_decode_errors: u32,
    /// Bus payloads dropped because the pool was exhausted.
    pub rx_dropped: u32,
}

fn bump(c: &mut u32) {
    *c = c.saturating_add(1);
}

/// Block ownership. `waker` is the publisher waiting for a free block or for room in
/// the engine queue (one publisher per topic).
struct PoolState<const N: usize> {
    /// Bit i: block i is allocated. Zero is "all free", the zeroed initial state.
    used: u32,
    refs: [u8; N],
    stamps: [Nanos; N],
    waker: Option<Waker>,
    /// The publisher's waker is to be called once the critical section ends.
    publisher_due: bool,
    /// Some waker (publisher's or a subscriber's) is due: checked once per section.
    wake_due: bool,
}

impl<const N: usize> PoolState<N> {
    const ALL: u32 = if N >= 32 { u32::MAX } else { (1u32 << N) - 1 };

    #[inline(always)]
    fn alloc(&mut self) -> Option<u8> {
        let free = !self.used & Self::ALL;
        if free == 0 {
            return None;
        }
        let idx = free.trailing_zeros();
        self.used |= 1u32 << idx;
        // idx < N ≤ 32, so it fits a u8.
        let idx = idx as u8;
        if let Some(r) = self.refs.get_mut(usize::from(idx)) {
            *r = 1;
        }
        Some(idx)
    }

    /// Sets the count of a block the caller owns alone; 0 frees it.
    #[inline(always)]
    fn set_refs(&mut self, idx: u8, refs: u8) {
        if refs == 0 {
            self.free_block(idx);
        } else if let Some(r) = self.refs.get_mut(usize::from(idx)) {
            *r = refs;
        }
    }

    #[inline(always)]
    fn unref(&mut self, idx: u8) {
        if let Some(r) = self.refs.get_mut(usize::from(idx)) {
            if *r == 0 {
                return; // not held: a stale token; freeing twice would corrupt the pool
            }
            *r -= 1;
            if *r == 0 {
                self.free_block(idx);
            }
        }
    }

    fn free_block(&mut self, idx: u8) {
        if let Some(r) = self.refs.get_mut(usize::from(idx)) {
            *r = 0;
        }
        self.used &= !bit(idx);
        self.wake_publisher();
    }

    /// Marks the publisher's waker due (called after the critical section, see module doc).
    fn wake_publisher(&mut self) {
        if self.waker.is_some() {
            self.publisher_due = true;
            self.wake_due = true;
        }
    }

    fn stamp(&self, idx: u8) -> Nanos {
        self.stamps.get(usize::from(idx)).copied().unwrap_or(0)
    }

    fn free_count(&self) -> usize {
        (!self.used & Self::ALL).count_ones() as usize
    }
}

/// One subscriber's queue.
struct SubState<const Q: usize> {
    ring: Ring<Q>,
    overflows: u32,
    waker: Option<Waker>,
    /// `waker` is to be called once the critical section ends (a publish came).
    due: bool,
    last_rx: Option<Nanos>,
}

impl<const Q: usize> SubState<Q> {
    const EMPTY: Self = SubState {
        ring: Ring::EMPTY,
        overflows: 0,
        waker: None,
        due: false,
        last_rx: None,
    };
}

/// The bus side: the HRT latch, the blocks waiting for `Engine::submit`, and the
/// flags the publishing node reads.
struct RemoteState<const Q: usize> {
    /// Bit i: the bus side (HRT latch, engine queue or the engine) holds one reference
    /// to block i. Guards against a token released twice or never handed out.
    held: u32,
    /// The latched HRT block (`None` is zero: the initial state stays in .bss).
    latest: Option<u8>,
    pending: Ring<Q>,
    nothing_flag: bool,
    miss_flag: bool,
}

impl<const Q: usize> RemoteState<Q> {
    const EMPTY: Self = RemoteState {
        held: 0,
        latest: None,
        pending: Ring::EMPTY,
        nothing_flag: false,
        miss_flag: false,
    };
}

struct State<const N: usize, const S: usize, const Q: usize> {
    pool: PoolState<N>,
    subs: [SubState<Q>; S],
    remote: RemoteState<Q>,
    stats: TopicStats,
}

impl<const N: usize, const S: usize, const Q: usize> State<N, S, Q> {
    /// Takes one due waker out (inside the critical section); clears the mark when none
    /// is left.
    fn take_one_due(&mut self) -> Option<Waker> {
        if core::mem::take(&mut self.pool.publisher_due) {
            if let Some(w) = self.pool.waker.take() {
                return Some(w);
            }
        }
        for sub in self.subs.iter_mut() {
            if core::mem::take(&mut sub.due) {
                if let Some(w) = sub.waker.take() {
                    return Some(w);
                }
            }
        }
        self.pool.wake_due = false;
        None
    }
}

/// A topic of message type `T` with `N` pool blocks, `S` local subscribers (slots
/// assigned at compile time) and queues of `Q` messages (also the depth of the queue
/// towards the engine). Size `N` with [`pool_blocks`].
///
/// Both are `const` (see the module doc for why two statics):
/// ```ignore
/// static SPEED_CELLS: TopicCells<Speed, 8, 2, 3> = TopicCells::new();
/// static SPEED: Topic<Speed, 8, 2, 3> = Topic::new(&SPEED_CELLS, Remote::None, None);
/// ```
pub struct Topic<T: Message, const N: usize, const S: usize, const Q: usize> {
    cells: &'static TopicCells<T, N, S, Q>,
    remote: Remote,
    kick: Option<fn()>,
}

/// The mutable part of a [`Topic`]: pool blocks, wire encodings and the bookkeeping.
/// All-zero initial value (.bss); used only through the `Topic` that refers to it.
pub struct TopicCells<T: Message, const N: usize, const S: usize, const Q: usize> {
    values: [UnsafeCell<MaybeUninit<T>>; N],
    wire: [UnsafeCell<T::Wire>; N],
    state: Mutex<RefCell<State<N, S, Q>>>,
}

// SAFETY: the cells are accessed under the ownership discipline in the module doc:
// a block is written only by its single owner and read only while referenced, and all
// bookkeeping is inside a critical section. `T: Send` because values cross contexts.
unsafe impl<T: Message, const N: usize, const S: usize, const Q: usize> Sync
    for TopicCells<T, N, S, Q>
{
}

impl<T: Message, const N: usize, const S: usize, const Q: usize> TopicCells<T, N, S, Q> {
    /// Empty cells: every block free, no subscriber message, no counter. All bytes zero.
    pub const fn new() -> Self {
        const {
            assert!(N >= 1 && N <= 32, "a topic pool has 1..=32 blocks");
            assert!(Q >= 1 && Q <= 255, "queue length 1..=255");
            assert!(S + 3 <= 255, "refcounts are u8");
            assert!(
                core::mem::size_of::<T::Wire>() == T::SIZE,
                "Message::Wire must be [u8; SIZE]"
            );
        }
        TopicCells {
            values: [const { UnsafeCell::new(MaybeUninit::uninit()) }; N],
            wire: [const { UnsafeCell::new(<T::Wire as WireBuf>::ZERO) }; N],
            state: Mutex::new(RefCell::new(State {
                pool: PoolState {
                    used: 0,
                    refs: [0; N],
                    stamps: [0; N],
                    waker: None,
                    publisher_due: false,
                    wake_due: false,
                },
                subs: [const { SubState::EMPTY }; S],
                remote: RemoteState::EMPTY,
                stats: TopicStats {
                    published: 0,
                    pool_exhausted: 0,
                    remote_overflows: 0,
                    hrt_replaced: 0,
                    nothing_to_send: 0,
                    sent: 0,
                    deadline_misses: 0,
                    not_submittable: 0,
                    rx_decode_errors: 0,
                    rx_dropped: 0,
                },
            })),
        }
    }
}

impl<T: Message, const N: usize, const S: usize, const Q: usize> Default
    for TopicCells<T, N, S, Q>
{
    fn default() -> Self {
        Self::new()
    }
}

/// Blocks a topic needs so that no publish fails while every queue is full: one per
/// queued message of each subscriber (`subscribers * queue`), one held by each
/// subscriber while it processes (`subscribers`), the engine's share (`remote`: 2 for
/// HRT = latched + on air, queue depth + 1 for SRT/NRT, 0 if local), and the
/// publisher's loans (`loans`, usually 1). HRT: a last fragment still retransmitting
/// when the next transfer starts keeps its block until it completes (the engine reports
/// each transfer once, when it is really over); a publish in that moment can find the
/// pool one block short (`PoolExhausted`, counted) unless `remote` is 3.
pub const fn pool_blocks(subscribers: usize, queue: usize, remote: usize, loans: usize) -> usize {
    subscribers * queue + subscribers + remote + loans
}

/// Why a subscriber got no message.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum RecvError {
    /// Queue empty, and the last message is recent enough.
    Empty,
    /// Queue empty and the last message is older than the allowed age (or none came yet).
    Stale,
}

impl<T: Message, const N: usize, const S: usize, const Q: usize> Topic<T, N, S, Q> {
    /// A topic over `cells` (its own, used by no other topic); `remote` says whether
    /// and how it is sent on the bus, `kick` is called
    /// (outside any critical section) after a message was queued for the engine, e.g.
    /// to pend the interrupt that runs `ModuleHost::pump`.
    pub const fn new(
        cells: &'static TopicCells<T, N, S, Q>,
        remote: Remote,
        kick: Option<fn()>,
    ) -> Self {
        Topic {
            cells,
            remote,
            kick,
        }
    }

    /// How this topic leaves the module.
    #[inline]
    pub fn remote(&self) -> Remote {
        self.remote
    }

    /// Counters.
    pub fn stats(&self) -> TopicStats {
        self.with_quiet(|st| st.stats)
    }

    /// Free pool blocks now.
    /// Back to the state of `new`, as far as the topic itself is concerned: drops the
    /// references held by the subscriber queues and the bus side (latched HRT sample,
    /// blocks waiting for or held by an engine), clears counters, flags, wakers and
    /// receive times. Blocks still held by a live `Msg` or `Loan` stay allocated until
    /// that handle drops, so this is safe at any time; it is meant for restarting a
    /// module (the simulator runs several robots one after another in one process).
    /// The engine that held bus-side blocks must be discarded with it.
    pub fn reset(&self) {
        self.with(|st| {
            for sub in st.subs.iter_mut() {
                while let Some(idx) = sub.ring.pop() {
                    st.pool.unref(idx);
                }
                *sub = SubState::EMPTY;
            }
            let held = st.remote.held;
            for idx in 0..32u8 {
                if held & bit(idx) != 0 {
                    st.pool.unref(idx);
                }
            }
            st.remote = RemoteState::EMPTY;
            st.pool.waker = None;
            st.pool.publisher_due = false;
            st.pool.wake_due = false;
            st.stats = TopicStats::default();
        });
    }

    pub fn free_blocks(&self) -> usize {
        self.with_quiet(|st| st.pool.free_count())
    }

    /// Runs `f` on the state in a critical section, then calls the wakers `f` made due,
    /// outside of it (a waker may re-enter this topic). The common path only reads a flag.
    #[inline(always)]
    fn with<R>(&self, f: impl FnOnce(&mut State<N, S, Q>) -> R) -> R {
        let (r, due) = critical_section::with(|cs| {
            let mut st = self.cells.state.borrow_ref_mut(cs);
            let r = f(&mut st);
            (r, st.pool.wake_due)
        });
        if due {
            self.wake_due();
        }
        r
    }

    /// `with` for sections that free no block and queue nothing (reads, alloc, pop,
    /// flags), so they make no waker due: no flag to check on the way out.
    #[inline(always)]
    fn with_quiet<R>(&self, f: impl FnOnce(&mut State<N, S, Q>) -> R) -> R {
        critical_section::with(|cs| f(&mut self.cells.state.borrow_ref_mut(cs)))
    }

    /// Takes the due wakers out one by one, each in a critical section of its own, and
    /// calls each after its section (whoever takes one calls it: none is lost or called
    /// twice).
    #[cold]
    #[inline(never)]
    fn wake_due(&self) {
        while let Some(w) =
            critical_section::with(|cs| self.cells.state.borrow_ref_mut(cs).take_one_due())
        {
            w.wake();
        }
    }

    /// The value cell of block `idx`.
    #[allow(clippy::indexing_slicing)] // idx < N: block indices come only from `PoolState::alloc`
    #[inline(always)]
    pub(crate) fn value_cell(&self, idx: u8) -> &UnsafeCell<MaybeUninit<T>> {
        &self.cells.values[usize::from(idx)]
    }

    // ---- pool -------------------------------------------------------------

    /// Takes a free block (refcount 1, owned by the caller) and writes `value` into it.
    #[inline(always)]
    pub(crate) fn alloc_idx(&self, value: T, waker: Option<&Waker>) -> Option<u8> {
        let idx = self.with_quiet(|st| match st.pool.alloc() {
            Some(i) => Some(i),
            None => {
                bump(&mut st.stats.pool_exhausted);
                if let Some(w) = waker {
                    register(&mut st.pool.waker, w);
                }
                None
            }
        })?;
        // SAFETY: the block was free and is now owned by us alone.
        unsafe { (*self.value_cell(idx).get()).write(value) };
        Some(idx)
    }

    /// Drops one reference.
    #[inline(always)]
    pub(crate) fn release(&self, idx: u8) {
        self.with(|st| st.pool.unref(idx));
    }

    /// Publishes the owned block `idx`, stamped `now`. Returns `false` (and does nothing,
    /// after registering `waker`) when an SRT or NRT topic's queue towards the engine is
    /// full: the message is neither sent nor half-published to the local subscribers.
    #[inline(always)]
    pub(crate) fn publish_idx(&self, idx: u8, now: Nanos, waker: Option<&Waker>) -> bool {
        if self.remote != Remote::None {
            // SAFETY: block `idx` is owned by the publisher alone until the critical
            // section below hands it out; its value was initialised by `alloc_idx`.
            unsafe {
                let v = (*self.value_cell(idx).get()).assume_init_ref();
                #[allow(clippy::indexing_slicing)] // idx < N, see value_cell
                v.encode((*self.cells.wire[usize::from(idx)].get()).as_mut());
            }
        }
        let mut kick = false;
        let accepted = self.with(|st| {
            if matches!(self.remote, Remote::Srt | Remote::Nrt) && st.remote.pending.is_full() {
                if self.remote == Remote::Srt {
                    bump(&mut st.stats.remote_overflows);
                }
                if let Some(w) = waker {
                    register(&mut st.pool.waker, w);
                }
                return false;
            }
            let mut refs = fan_out(st, idx, now);
            match self.remote {
                Remote::None => {}
                Remote::Hrt => {
                    let old = st.remote.latest.replace(idx);
                    refs += 1;
                    st.remote.held |= bit(idx);
                    if let Some(old) = old {
                        st.remote.held &= !bit(old);
                        st.pool.unref(old);
                        bump(&mut st.stats.hrt_replaced);
                    }
                }
                Remote::Srt | Remote::Nrt => {
                    // Room was checked above, in this critical section.
                    if st.remote.pending.push(idx) {
                        refs += 1;
                        st.remote.held |= bit(idx);
                        kick = true;
                    }
                }
            }
            // The publisher's reference becomes the queues' references.
            st.pool.set_refs(idx, refs);
            true
        });
        if kick {
            if let Some(k) = self.kick {
                k();
            }
        }
        accepted
    }

    /// Alloc + write + publish of a local-only topic in one critical section: the
    /// hot path of local publish (nothing to encode, nobody to refuse).
    #[inline(always)]
    pub(crate) fn send_local(&self, value: T, now: Nanos) -> bool {
        self.with(|st| {
            let Some(idx) = st.pool.alloc() else {
                bump(&mut st.stats.pool_exhausted);
                return false;
            };
            // SAFETY: the block was free; nothing else can reach it inside this
            // critical section before `fan_out` hands it to the subscribers.
            unsafe { (*self.value_cell(idx).get()).write(value) };
            let refs = fan_out(st, idx, now);
            st.pool.set_refs(idx, refs);
            true
        })
    }

    // ---- subscribers ------------------------------------------------------

    /// Pops subscriber `id`'s oldest message: (block, stamp).
    #[inline(always)]
    pub(crate) fn pop(&self, id: u8, waker: Option<&Waker>) -> Option<(u8, Nanos)> {
        self.with_quiet(|st| {
            let sub = st.subs.get_mut(usize::from(id))?;
            match sub.ring.pop() {
                Some(idx) => {
                    let stamp = st.pool.stamp(idx);
                    sub.last_rx = Some(stamp);
                    Some((idx, stamp))
                }
                None => {
                    if let Some(w) = waker {
                        register(&mut sub.waker, w);
                    }
                    None
                }
            }
        })
    }

    /// Like `pop`, but an empty queue is `Stale` when the last message is older than
    /// `max_age` at `now` (or none came yet).
    pub(crate) fn pop_or_stale(
        &self,
        id: u8,
        now: Nanos,
        max_age: Nanos,
    ) -> Result<(u8, Nanos), RecvError> {
        match self.pop(id, None) {
            Some(m) => Ok(m),
            None => match self.last_rx(id) {
                Some(t) if now.saturating_sub(t) <= max_age => Err(RecvError::Empty),
                _ => Err(RecvError::Stale),
            },
        }
    }

    pub(crate) fn last_rx(&self, id: u8) -> Option<Nanos> {
        self.with_quiet(|st| st.subs.get(usize::from(id)).and_then(|s| s.last_rx))
    }

    pub(crate) fn overflows(&self, id: u8) -> u32 {
        self.with_quiet(|st| st.subs.get(usize::from(id)).map_or(0, |s| s.overflows))
    }

    pub(crate) fn queued(&self, id: u8) -> usize {
        self.with_quiet(|st| st.subs.get(usize::from(id)).map_or(0, |s| s.ring.len()))
    }

    // ---- publisher flags --------------------------------------------------

    pub(crate) fn take_nothing_flag(&self) -> bool {
        self.with_quiet(|st| core::mem::take(&mut st.remote.nothing_flag))
    }

    pub(crate) fn take_miss_flag(&self) -> bool {
        self.with_quiet(|st| core::mem::take(&mut st.remote.miss_flag))
    }

    // ---- engine side (used by the ports) ------------------------------------

    /// HRT slot: hands the latched block to the engine (its reference moves along).
    pub(crate) fn hrt_take(&self) -> Option<Token> {
        self.with_quiet(|st| {
            let idx = st.remote.latest.take();
            if idx.is_none() {
                // Counted here, where it is known; the `NothingToSend` outcome that
                // follows only raises the flag again, so each empty slot counts once.
                bump(&mut st.stats.nothing_to_send);
                st.remote.nothing_flag = true;
            }
            idx.map(|i| Token(u16::from(i)))
        })
    }

    /// When the block the engine holds as `token` was published (the `now` given to
    /// `send`/`publish`); `None` for a token the bus side does not hold.
    pub(crate) fn engine_stamp(&self, token: Token) -> Option<Nanos> {
        let idx = u8::try_from(token.0).ok()?;
        self.with_quiet(|st| (st.remote.held & bit(idx) != 0).then(|| st.pool.stamp(idx)))
    }

    /// The engine finished with `token`.
    pub(crate) fn engine_done(&self, token: Option<Token>, outcome: TxOutcome) {
        self.with(|st| {
            match outcome {
                TxOutcome::Sent => bump(&mut st.stats.sent),
                TxOutcome::DeadlineMissed => {
                    bump(&mut st.stats.deadline_misses);
                    st.remote.miss_flag = true;
                }
                TxOutcome::NothingToSend => st.remote.nothing_flag = true,
            }
            if let Some(idx) = token.and_then(|t| u8::try_from(t.0).ok()) {
                if st.remote.held & bit(idx) != 0 {
                    st.remote.held &= !bit(idx);
                    st.pool.unref(idx);
                }
            }
        })
    }

    /// Oldest block waiting for `Engine::submit`.
    pub(crate) fn pending_peek(&self) -> Option<Token> {
        self.with_quiet(|st| st.remote.pending.peek().map(|i| Token(u16::from(i))))
    }

    /// Removes `token` from the head of the engine queue: its reference moves to the
    /// engine (`accepted`) or is dropped (refused by the engine, counted).
    pub(crate) fn pending_pop(&self, token: Token, accepted: bool) {
        self.with(|st| {
            if st.remote.pending.peek().map(|i| Token(u16::from(i))) != Some(token) {
                return;
            }
            let _ = st.remote.pending.pop();
            if !accepted {
                bump(&mut st.stats.not_submittable);
                if let Ok(idx) = u8::try_from(token.0) {
                    st.remote.held &= !bit(idx);
                    st.pool.unref(idx);
                }
            }
            // Room in the engine queue: an NRT publisher may be waiting for it.
            st.pool.wake_publisher();
        })
    }

    /// Encoded bytes of a block the engine holds; empty for an unknown or free token.
    pub(crate) fn wire_bytes(&self, token: Token) -> &[u8] {
        let Ok(idx) = u8::try_from(token.0) else {
            return &[];
        };
        let Some(cell) = self.cells.wire.get(usize::from(idx)) else {
            return &[];
        };
        if !self.with_quiet(|st| st.remote.held & bit(idx) != 0) {
            return &[];
        }
        // SAFETY: the bus side holds a reference to the block, so nobody writes it.
        unsafe { (*cell.get()).as_ref() }
    }

    /// A payload from the bus: decoded into a block and published to the local
    /// subscribers, stamped with the start-of-frame time.
    pub(crate) fn deliver_bytes(&self, bytes: &[u8], sof: Nanos) {
        let Some(value) = T::decode(bytes) else {
            self.with_quiet(|st| bump(&mut st.stats.rx_decode_errors));
            return;
        };
        match self.alloc_idx(value, None) {
            Some(idx) => {
                if !self.publish_idx(idx, sof, None) {
                    // Only an SRT/NRT topic sent by this module refuses; a module does
                    // not both send and receive one topic, but the block must not leak.
                    self.release(idx);
                    self.with_quiet(|st| bump(&mut st.stats.rx_dropped));
                }
            }
            None => self.with_quiet(|st| bump(&mut st.stats.rx_dropped)),
        }
    }
}

/// Queues block `idx` to every local subscriber, stamped `now`; returns how many
/// references the queues took. Counts the publish.
#[inline(always)]
fn fan_out<const N: usize, const S: usize, const Q: usize>(
    st: &mut State<N, S, Q>,
    idx: u8,
    now: Nanos,
) -> u8 {
    if let Some(s) = st.pool.stamps.get_mut(usize::from(idx)) {
        *s = now;
    }
    let mut refs: u8 = 0;
    for sub in st.subs.iter_mut() {
        if sub.ring.is_full() {
            // A slow subscriber loses its oldest message, counted; the publisher and
            // the other subscribers are not affected.
            if let Some(old) = sub.ring.pop() {
                st.pool.unref(old);
            }
            bump(&mut sub.overflows);
        }
        if sub.ring.push(idx) {
            refs += 1;
        }
        if sub.waker.is_some() {
            // Taken and called by `Topic::with` once the critical section ends.
            sub.due = true;
            st.pool.wake_due = true;
        }
    }
    // Wrapping: a rate counter, read as differences (saturating costs the hot path).
    st.stats.published = st.stats.published.wrapping_add(1);
    refs
}

/// Mask bit of block `idx` (< 32).
#[inline(always)]
fn bit(idx: u8) -> u32 {
    1u32 << (idx & 31)
}

/// Stores `w` unless the stored waker already wakes the same task.
fn register(slot: &mut Option<Waker>, w: &Waker) {
    match slot {
        Some(old) if old.will_wake(w) => {}
        _ => *slot = Some(w.clone()),
    }
}
