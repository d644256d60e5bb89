// The RTIC 2 app every module image runs, included by src/bin/<module>.rs after it
// names, at its root: `fw` (this crate), `module` (its `rtcan::robot_toml::<module>`),
// `App` (its app of `triskar2_nodes::app`), `Hw` (its hardware of `fw::io`) and `NAME`.
// RTIC's `#[app]` needs the whole module in one item, hence `include!` and not a
// function or a trait.
//
// Hardware tasks (slot timer, CAN RX0/TX/SCE, kick) share priority 4 and the `Driver`;
// the app task runs at priority 1: `poll(now, hw)` at its due times and after every
// delivery of a received message, as the simulator calls it.

#[rtic::app(device = rtcan_board_stm32f103::hal::pac, dispatchers = [EXTI2])]
mod app {
    use super::{fw, module, App, Hw, NAME};
    use fw::board::FromBoard;
    use fw::driver::Driver;
    use rtcan_board_stm32f103::filter_set;

    type Drv = Driver<{ module::RX_COUNT }, { module::ARENA_BYTES }, { module::QUEUE_CAPACITY }>;

    #[shared]
    struct Shared {
        drv: Drv,
    }

    #[local]
    struct Local {
        hw: Hw,
    }

    #[init]
    fn init(cx: init::Context) -> (Shared, Local) {
        let (bus, board) = fw::board::init(cx.device, filter_set!(module::FILTERS));
        fw::Mono::start(cx.core.SYST, fw::SYSCLK_HZ);
        let hw = Hw::from_board(board);
        let mut drv = Drv::new(module::engine(bus.timer.now()), bus, module::host());
        drv.start();
        if module_app::spawn().is_err() {
            defmt::error!("app task was already running");
        }
        defmt::info!("{=str} up", NAME);
        (Shared { drv }, Local { hw })
    }

    #[task(binds = TIM2, shared = [drv], priority = 4)]
    fn slot_timer(mut cx: slot_timer::Context) {
        cx.shared.drv.lock(|d| d.on_timer());
    }

    #[task(binds = USB_LP_CAN_RX0, shared = [drv], priority = 4)]
    fn can_rx(mut cx: can_rx::Context) {
        cx.shared.drv.lock(|d| d.on_rx());
    }

    #[task(binds = USB_HP_CAN_TX, shared = [drv], priority = 4)]
    fn can_tx(mut cx: can_tx::Context) {
        cx.shared.drv.lock(|d| d.on_tx());
    }

    #[task(binds = CAN_SCE, shared = [drv], priority = 4)]
    fn can_sce(mut cx: can_sce::Context) {
        cx.shared.drv.lock(|d| d.on_sce());
    }

    #[task(binds = EXTI1, shared = [drv], priority = 4)]
    fn kick(mut cx: kick::Context) {
        cx.shared.drv.lock(|d| d.on_kick());
    }

    /// The module's app on the slot timer's clock (the clock of message stamps).
    #[task(shared = [drv], local = [hw], priority = 1)]
    async fn module_app(mut cx: module_app::Context) {
        let mut app = App::new();
        let mut safe = fw::run::SafeLog::new();
        loop {
            let now = cx.shared.drv.lock(|d| d.now());
            let due = app.poll(now, cx.local.hw);
            // What the app published for SRT/NRT waits in its topics: hand it over.
            fw::driver::kick();
            safe.update(&module::STATUS);
            fw::run::sleep_until(now, due).await;
        }
    }
}
