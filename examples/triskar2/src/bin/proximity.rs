//! Module `proximity`: four Sharp IR rangers (node `ir_ranger`, 25 Hz, publishes
//! `proximity`) and the obstacle override (node `obstacle_avoid`, 50 Hz, `teleop` +
//! `proximity` → `velocity`).
#![no_std]
#![no_main]

use triskar2_firmware as fw;

#[rtic::app(device = rtcan_board_stm32f103::hal::pac, dispatchers = [EXTI2, EXTI3, EXTI4])]
mod app {
    use super::fw;
    use fw::driver::Driver;
    use fw::robot::proximity as module;
    use module::nodes::{ir_ranger, obstacle_avoid};
    use rtcan_board_stm32f103::filter_set;

    type Drv = Driver<{ module::RX_COUNT }, { module::ARENA_BYTES }, { module::QUEUE_CAPACITY }>;

    #[shared]
    struct Shared {
        drv: Drv,
    }

    #[local]
    struct Local {
        rangers: fw::io::Analog4,
    }

    #[init]
    fn init(cx: init::Context) -> (Shared, Local) {
        let mut b = fw::board::init(cx.device, filter_set!(module::FILTERS));
        fw::Mono::start(cx.core.SYST, fw::SYSCLK_HZ);
        let rangers = fw::io::Analog4::new(b.adc1, b.pins.adc, &mut b.pins.a_crl, &mut b.rcc);
        let mut drv = Driver {
            engine: module::engine(b.timer.now()),
            can: b.can,
            timer: b.timer,
            host: module::host(),
        };
        drv.start();
        fw::spawned(ir_ranger_task::spawn(), "ir_ranger");
        fw::spawned(obstacle_avoid_task::spawn(), "obstacle_avoid");
        fw::spawned(supervisor::spawn(), "supervisor");
        defmt::info!("proximity up");
        (Shared { drv }, Local { rangers })
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
    #[task(shared = [drv], local = [rangers], priority = 2)]
    async fn ir_ranger_task(mut cx: ir_ranger_task::Context) {
        fw::tasks::ir_ranger(
            &ir_ranger::NODE,
            &module::STATUS,
            cx.local.rangers,
            ir_ranger::proximity_pub(),
            || cx.shared.drv.lock(|d| d.now()),
        )
        .await
    }

    #[task(shared = [drv], priority = 3)]
    async fn obstacle_avoid_task(mut cx: obstacle_avoid_task::Context) {
        fw::tasks::obstacle_avoid(
            &obstacle_avoid::NODE,
            &module::STATUS,
            obstacle_avoid::teleop_sub(),
            obstacle_avoid::proximity_sub(),
            obstacle_avoid::velocity_pub(),
            || cx.shared.drv.lock(|d| d.now()),
        )
        .await
    }

    #[task(priority = 1)]
    async fn supervisor(_cx: supervisor::Context) {
        fw::tasks::supervisor(&module::STATUS).await
    }
}
