/// The RTIC 2 app every module image runs. Invoke it at the root of a bin
/// (`src/bin/<module>.rs`) after naming there: `fw` (this crate, or a crate re-exporting
/// its `board`, `driver`, `run`, `cycles`, `Mono` and `SYSCLK_HZ`), `robot` (the generated
/// robot: `rtcan::robot_toml` or a `rtcan::robot!` module), `module` (its
/// `robot::<module>`), `App` (the module's app: `App::new()` and
/// `poll(&mut self, now, &mut Hw) -> next due time`), `Hw` (its hardware, `FromBoard`),
/// `NAME` and `STAMPS` (the board's SOF timestamp strategy). The bin's crate depends on
/// `rtic`, `rtcan-board-stm32f103`, `cortex-m`, `heapless` and `defmt` (the app's code
/// names them). RTIC's `#[app]` needs the whole module in one item, hence a macro and
/// not a function or a trait; Triskar2 and every workspace written by `rtcan new` share
/// it.
//
// Split interrupt architecture (boards/common `protocol`, priorities in `fw::driver`):
// the slot timer (4) only commits the plan the protocol task (2) prepared; CAN RX/TX/SCE
// (3) only move registers into lock-free queues; the app (1) polls its nodes; SysTick is
// set below everything. Only the slot-timer resource is shared across priorities (RTIC
// priority ceilings: its critical sections are the slot timer's only blocking).
// `critical_section::with` (topics, status, `run::DUE`) raises BASEPRI to the protocol
// task's priority only (boards/stm32f103 `ceiling`): it never blocks priorities 3 and 4.
#[macro_export]
macro_rules! module_app {
    () => {
/// CAN bit timing register for robot.toml's bit rate (a compile error if PCLK1 cannot
/// produce it exactly).
const BTR: u32 =
    rtcan_board_stm32f103::can_btr!(rtcan_board_stm32f103::PCLK1_HZ, robot::BUS.bitrate);

// The `priority = ...` literals of the tasks below (RTIC takes literals only) against the
// one source of the critical-section ceiling, `PROTOCOL_PRIORITY` (boards/stm32f103
// `ceiling`): the protocol task at it, the slot timer and CAN interrupts above it (they
// never enter a critical section and are never blocked by one), the app task below.
const _: () = {
    use rtcan_board_stm32f103::ceiling::PROTOCOL_PRIORITY;
    assert!(PROTOCOL_PRIORITY == 2, "the protocol task's `priority = 2` disagrees with PROTOCOL_PRIORITY");
    assert!(4 > PROTOCOL_PRIORITY, "the slot timer (priority 4) must be above the ceiling");
    assert!(3 > PROTOCOL_PRIORITY, "the CAN interrupts (priority 3) must be above the ceiling");
    assert!(1 <= PROTOCOL_PRIORITY, "the app task (priority 1) must be at or below the ceiling");
};

#[rtic::app(device = rtcan_board_stm32f103::hal::pac, dispatchers = [EXTI2])]
mod app {
    use super::{fw, module, robot, App, Hw, BTR, NAME, STAMPS};
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
    }

    #[local]
    struct Local {
        hw: Hw,
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
        );
        // The protocol task's first run (right after init) arms the first wake-up.
        pend_protocol();
        if module_app::spawn().is_err() {
            defmt::error!("app task was already running");
        }
        defmt::info!("{=str} up", NAME);
        (
            Shared { slot, tx_events },
            Local {
                hw,
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
    #[task(binds = TIM2, shared = [slot], priority = 4)]
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
    #[task(binds = USB_LP_CAN_RX0, shared = [slot], local = [can_rx, rx_events], priority = 3)]
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
    #[task(binds = USB_HP_CAN_TX, shared = [tx_events], local = [can_tx_irq], priority = 3)]
    fn can_tx(mut cx: can_tx::Context) {
        let t = fw::cycles::now();
        let irq = cx.local.can_tx_irq;
        cx.shared.tx_events.lock(|q| irq.on_interrupt(q));
        pend_protocol();
        fw::cycles::ISR_CAN_TX.since(t);
    }

    /// Error counters; bus-off aborts every mailbox at once and blocks the prepared plan
    /// (the slot timer must not load it before the protocol task has seen the bus-off).
    #[task(binds = CAN_SCE, shared = [slot, tx_events], local = [can_sce], priority = 3)]
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
    #[task(binds = EXTI1, shared = [slot], local = [drv, rx_queue, tx_queue], priority = 2)]
    fn protocol(cx: protocol::Context) {
        let mut slot = Rtic(cx.shared.slot);
        cx.local.drv.run(cx.local.rx_queue, cx.local.tx_queue, &mut slot);
    }

    /// The module's app on the slot timer's clock (the clock of message stamps).
    #[task(shared = [slot], local = [hw, watchdog], priority = 1)]
    async fn module_app(mut cx: module_app::Context) {
        let mut app = App::new();
        let mut safe = fw::run::SafeLog::new();
        let mut last_report = 0;
        loop {
            cx.local.watchdog.feed();
            let ticks = cx.shared.slot.lock(|c| c.timer.ticks());
            let now = rtcan_board_stm32f103::slot_timer::SlotTimer::ns_of(ticks);
            fw::cycles::report(now, &mut last_report);
            let due = app.poll(now, cx.local.hw);
            // What the app published for SRT/NRT waits in its topics: hand it over.
            fw::driver::kick();
            safe.update(&module::STATUS);
            fw::run::sleep_until(now, due).await;
        }
    }
}
    };
}
