/// The RTIC 2 app every module image runs, one async software task per node robot.toml
/// places on the module, at the node's priority. The per-module invocation is generated
/// from robot.toml (`rtcan_codegen::apps::rtic_app_macro`, a `<module>_app!` macro of the
/// nodes crate, Triskar2's and every workspace `rtcan new` writes): a bin invokes that
/// after naming `fw` (this crate, or a crate re-exporting its `board`, `driver`, `run`,
/// `cycles`, `Mono`, `SYSCLK_HZ` and a `Locked` hardware proxy implementing the nodes'
/// hardware traits), `robot` (the generated robot), `module` (its `robot::<module>`),
/// `Hw` (the module's hardware, `FromBoard`), `NAME` and `STAMPS` (the board's SOF
/// timestamp strategy). The bin's crate depends on `rtic`, `rtcan-board-stm32f103`,
/// `cortex-m`, `heapless` and `defmt` (the app's code names them). RTIC's `#[app]` needs
/// the whole module in one item with literal tasks and priorities, hence a macro fed by
/// the generator and not a function or a trait.
///
/// Input (generated): `dispatchers` (one free interrupt per node priority level used),
/// `nodes` (index into `WAKES`, task name, RTIC priority, path of the node's task module
/// with `new()` and `poll(&mut Task, now, &mut impl Hw) -> next due`, whether remote
/// deliveries wake it, the indices of the local nodes subscribing to what it publishes),
/// in ascending priority; `ceilings` (each topic's ceiling: the highest priority of its
/// accessors on the module, the protocol task's if it crosses the bus).
//
// Split interrupt architecture (boards/common `protocol`, priorities in `fw::driver`):
// the slot timer (15) only commits the plan the protocol task (13) prepared; CAN
// RX/TX/SCE (14) only move registers into lock-free queues; the node tasks (1..=12) poll
// their nodes; idle feeds the watchdog; SysTick is set below everything. The slot-timer
// resource is shared across the interrupt priorities (RTIC priority ceilings: its
// critical sections are the slot timer's only blocking); the module's hardware is shared
// by its node tasks (ceiling: the highest of them; a single node's lock is free).
// `critical_section::with` (topics, status, the wake-ups) raises BASEPRI to the protocol
// task's priority only (boards/stm32f103 `ceiling`): it never blocks priorities 14 and 15.
#[macro_export]
macro_rules! module_app {
    (
        dispatchers: [$($dispatcher:ident),* $(,)?],
        nodes: [$({
            index: $index:tt,
            name: $name:ident,
            priority: $prio:tt,
            task: $($task:ident)::+,
            on_delivery: $on_delivery:tt,
            wakes: [$($wake:tt),* $(,)?] $(,)?
        }),* $(,)?],
        ceilings: [$($topic:ident = $ceiling:tt),* $(,)?] $(,)?
    ) => {
/// CAN bit timing register for robot.toml's bit rate (a compile error if PCLK1 cannot
/// produce it exactly).
const BTR: u32 =
    rtcan_board_stm32f103::can_btr!(rtcan_board_stm32f103::PCLK1_HZ, robot::BUS.bitrate);

/// Node tasks on this module (robot.toml's placement).
const NODE_COUNT: usize = [$(stringify!($name)),*].len();

/// Each node task's wake-up (due time on the slot clock, notify), by `index`: set by
/// the task, read by the protocol task.
static WAKES: [fw::run::Wake; NODE_COUNT] = [$(fw::run::Wake::new($on_delivery)),*];

// The literal priorities below (RTIC takes literals only) and the node band against the
// constants of `fw::driver`, whose `PROTOCOL_PRIORITY` is the one source of the
// critical-section ceiling (boards/stm32f103 `ceiling`): the protocol task at it, the
// slot timer and CAN interrupts above it (they never enter a critical section and are
// never blocked by one), the node tasks below.
const _: () = {
    assert!(fw::driver::PROTOCOL_PRIORITY == 13, "the protocol task's `priority = 13` disagrees with PROTOCOL_PRIORITY");
    assert!(fw::driver::PROTOCOL_PRIORITY == rtcan_board_stm32f103::ceiling::PROTOCOL_PRIORITY);
    assert!(fw::driver::CAN_PRIORITY == 14);
    assert!(fw::driver::SLOT_TIMER_PRIORITY == 15);
    $(assert!(
        $prio >= 1 && $prio <= fw::driver::NODE_PRIORITY_LEVELS,
        concat!("node `", stringify!($name), "`: robot.toml uses more node priority levels than fw::driver::NODE_PRIORITY_LEVELS")
    );)*
    // Topic sections are `critical_section` locks: each topic's ceiling must not exceed
    // the critical section's (the protocol task's priority).
    $(assert!(
        $ceiling <= fw::driver::PROTOCOL_PRIORITY,
        concat!("topic `", stringify!($topic), "`: ceiling above the protocol task's")
    );)*
};

#[rtic::app(device = rtcan_board_stm32f103::hal::pac, dispatchers = [$($dispatcher),*])]
mod app {
    use super::{fw, module, robot, Hw, BTR, NAME, STAMPS, WAKES};
    use cortex_m::peripheral::scb::SystemHandler;
    use fw::board::FromBoard;
    use fw::driver::{pend_protocol, Driver, Rtic, SlotCore, RX_QUEUE, TX_QUEUE};
    use heapless::spsc::{Consumer, Producer, Queue};
    use robot::BUS;
    use rtcan_board_stm32f103::common::{RxEvent, SlotPlan, TxEvent};
    use rtcan_board_stm32f103::hal::watchdog::IndependentWatchdog;
    use rtcan_board_stm32f103::{filter_set, glue, CanRx, CanSce, CanTxIrq};

    type Drv = Driver<{ module::RX_COUNT }, { module::ARENA_BYTES }, { module::QUEUE_CAPACITY }>;

    #[shared]
    struct Shared {
        /// TIM2, the prepared plan, the TX mailboxes: the slot timer's resource.
        slot: SlotCore,
        /// TX events, produced by the CAN TX and SCE interrupts (same priority).
        tx_events: Producer<'static, TxEvent>,
        /// The module's hardware, shared by its node tasks through `fw::Locked`.
        hw: Hw,
    }

    #[local]
    struct Local {
        watchdog: IndependentWatchdog,
        drv: Drv,
        can_rx: CanRx,
        rx_events: Producer<'static, RxEvent>,
        rx_queue: Consumer<'static, RxEvent>,
        tx_queue: Consumer<'static, TxEvent>,
        can_tx_irq: CanTxIrq,
        can_sce: CanSce,
    }

    #[init(local = [
        rxq: Queue<RxEvent, RX_QUEUE> = Queue::new(),
        txq: Queue<TxEvent, TX_QUEUE> = Queue::new(),
    ])]
    fn init(mut cx: init::Context) -> (Shared, Local) {
        let (bus, board) = fw::board::init(cx.device, BTR, filter_set!(module::FILTERS));
        fw::Mono::start(cx.core.SYST, fw::SYSCLK_HZ);
        fw::cycles::enable(&mut cx.core.DCB, &mut cx.core.DWT);
        // The monotonic leaves SysTick at priority 0 (the highest): below everything,
        // so a tick never delays a slot boundary or a received frame.
        // SAFETY: changes only SysTick's priority, before any task runs.
        unsafe { cx.core.SCB.set_priority(SystemHandler::SysTick, 0xF0) };
        let hw = Hw::from_board(board);
        let (rx_events, rx_queue) = cx.local.rxq.split();
        let (tx_events, tx_queue) = cx.local.txq.split();
        let slot = SlotCore {
            timer: bus.timer,
            plan: SlotPlan::new(),
            tx: bus.can.tx,
        };
        let drv = Drv::new(
            module::engine(slot.timer.now()),
            module::host(),
            BUS.bitrate,
            BUS.slot_ns,
            STAMPS,
            &WAKES,
        );
        // The protocol task's first run (right after init) arms the first wake-up.
        pend_protocol();
        // Spawned once, here: none can be running yet, so `spawn` cannot fail (and a log
        // line per node would cost flash the fullest image does not have).
        $(let _ = $name::spawn();)*
        defmt::info!("{=str} up", NAME);
        (
            Shared { slot, tx_events, hw },
            Local {
                watchdog: bus.watchdog,
                drv,
                can_rx: bus.can.rx,
                rx_events,
                rx_queue,
                tx_queue,
                can_tx_irq: bus.can.tx_irq,
                can_sce: bus.can.sce,
            },
        )
    }

    /// Slot boundaries and window-close aborts: prepared work only.
    #[task(binds = TIM2, shared = [slot], priority = 15)]
    fn slot_timer(mut cx: slot_timer::Context) {
        let t = fw::cycles::now();
        let (pend, since_match) = cx.shared.slot.lock(|c| {
            let pend = glue::on_slot_timer(c);
            let since = if fw::cycles::ENABLED {
                c.timer.ticks_since_commit_match()
            } else {
                0
            };
            (pend, since)
        });
        if pend {
            pend_protocol();
        }
        fw::cycles::ISR_SLOT_TIMER.since(t);
        if pend && fw::cycles::ENABLED {
            // 9 CPU cycles per 8 MHz tick.
            fw::cycles::SLOT_BOUNDARY_TO_TXRQ.add(u32::from(since_match) * 9);
        }
    }

    /// Received frames: registers and local time into the queue.
    #[task(binds = USB_LP_CAN_RX0, shared = [slot], local = [can_rx, rx_events], priority = 14)]
    fn can_rx(mut cx: can_rx::Context) {
        let t = fw::cycles::now();
        // Only the counter under the lock (it blocks the slot timer); ns outside.
        let ticks = cx.shared.slot.lock(|c| c.timer.ticks());
        let now = rtcan_board_stm32f103::slot_timer::SlotTimer::ns_of(ticks);
        cx.local.can_rx.on_interrupt(now, cx.local.rx_events);
        pend_protocol();
        fw::cycles::ISR_CAN_RX.since(t);
    }

    /// Mailbox completions into the queue.
    #[task(binds = USB_HP_CAN_TX, shared = [tx_events], local = [can_tx_irq], priority = 14)]
    fn can_tx(mut cx: can_tx::Context) {
        let t = fw::cycles::now();
        let irq = cx.local.can_tx_irq;
        cx.shared.tx_events.lock(|q| irq.on_interrupt(q));
        pend_protocol();
        fw::cycles::ISR_CAN_TX.since(t);
    }

    /// Error counters; bus-off aborts every mailbox at once and blocks the prepared plan
    /// (the slot timer must not load it before the protocol task has seen the bus-off).
    #[task(binds = CAN_SCE, shared = [slot, tx_events], local = [can_sce], priority = 14)]
    fn can_sce(mut cx: can_sce::Context) {
        let sce = cx.local.can_sce;
        let events = &mut cx.shared.tx_events;
        // Abort and block under the slot timer's ceiling: no commit can slip in between
        // the abort of every mailbox and the block (a few register accesses, only on a
        // status change).
        let change = cx.shared.slot.lock(|c| {
            let change = events.lock(|q| sce.on_interrupt(q));
            if change == rtcan_board_stm32f103::ErrorChange::BusOff {
                c.plan.block();
            }
            change
        });
        // Logged by the protocol task, below the critical-section ceiling.
        fw::driver::note_error_change(change);
        pend_protocol();
    }

    /// The protocol: everything the engine does, ahead of the slot timer.
    #[task(binds = EXTI1, shared = [slot], local = [drv, rx_queue, tx_queue], priority = 13)]
    fn protocol(cx: protocol::Context) {
        let mut slot = Rtic(cx.shared.slot);
        cx.local.drv.run(cx.local.rx_queue, cx.local.tx_queue, &mut slot);
    }

    /// Feeds the watchdog whenever no task runs, then sleeps: a node task that never
    /// yields starves it, and the watchdog resets the module.
    #[idle(shared = [hw], local = [watchdog])]
    fn idle(cx: idle::Context) -> ! {
        // `hw` is named so a module without nodes still uses it; idle never locks it.
        let _ = cx.shared.hw;
        loop {
            cx.local.watchdog.feed();
            cortex_m::asm::wfi();
        }
    }

    $(
    /// A node's task on the slot timer's clock (the clock of message stamps), at the
    /// node's robot.toml priority: poll, wake the local subscribers of what it
    /// published, sleep until its next due time or a message for it.
    #[task(shared = [slot, hw], priority = $prio)]
    async fn $name(cx: $name::Context) {
        let mut slot = cx.shared.slot;
        let mut hw = fw::Locked(cx.shared.hw);
        let wake = &WAKES[$index];
        let mut task = $($task)::+::new();
        // The lowest-priority node task (index 0) logs for the module.
        let mut safe = fw::run::SafeLog::new();
        let mut last_report = 0;
        loop {
            let ticks = slot.lock(|c| c.timer.ticks());
            let now = rtcan_board_stm32f103::slot_timer::SlotTimer::ns_of(ticks);
            if $index == 0 {
                fw::cycles::report(now, &mut last_report);
            }
            let due = $($task)::+::poll(&mut task, now, &mut hw);
            $(WAKES[$wake].notify();)*
            // What it published for SRT/NRT waits in its topics: hand it over.
            fw::driver::kick();
            if $index == 0 {
                safe.update(&module::STATUS);
            }
            wake.sleep_until(now, due).await;
        }
    }
    )*
}
    };
}
