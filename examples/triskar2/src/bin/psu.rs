//! Module `psu`: the battery monitor (node `battery_monitor`, 10 Hz sampling,
//! publishes `battery` at 1 Hz and `log` lines, both NRT).
#![no_std]
#![no_main]

use triskar2_firmware as fw;

#[rtic::app(device = rtcan_board_stm32f103::hal::pac, dispatchers = [EXTI2, EXTI3, EXTI4])]
mod app {
    use super::fw;
    use fw::driver::Driver;
    use fw::robot::psu as module;
    use module::nodes::battery_monitor;
    use rtcan_board_stm32f103::filter_set;

    type Drv = Driver<{ module::RX_COUNT }, { module::ARENA_BYTES }, { module::QUEUE_CAPACITY }>;

    #[shared]
    struct Shared {
        drv: Drv,
    }

    #[local]
    struct Local {
        adc: fw::io::Analog4,
    }

    #[init]
    fn init(cx: init::Context) -> (Shared, Local) {
        let mut b = fw::board::init(cx.device, filter_set!(module::FILTERS));
        fw::Mono::start(cx.core.SYST, fw::SYSCLK_HZ);
        let adc = fw::io::Analog4::new(b.adc1, b.pins.adc, &mut b.pins.a_crl, &mut b.rcc);
        let mut drv = Driver {
            engine: module::engine(b.timer.now()),
            can: b.can,
            timer: b.timer,
            host: module::host(),
        };
        drv.start();
        fw::spawned(battery_monitor_task::spawn(), "battery_monitor");
        fw::spawned(supervisor::spawn(), "supervisor");
        defmt::info!("psu up");
        (Shared { drv }, Local { adc })
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
    #[task(shared = [drv], local = [adc], priority = 1)]
    async fn battery_monitor_task(mut cx: battery_monitor_task::Context) {
        fw::tasks::battery_monitor(
            &battery_monitor::NODE,
            &module::STATUS,
            cx.local.adc,
            battery_monitor::battery_pub(),
            battery_monitor::log_pub(),
            || cx.shared.drv.lock(|d| d.now()),
        )
        .await
    }

    #[task(priority = 1)]
    async fn supervisor(_cx: supervisor::Context) {
        fw::tasks::supervisor(&module::STATUS).await
    }
}
