//! Module `motor2`: DC motor 2 (node `motor_ctrl2`, 200 Hz PID, publishes the local
//! topic `encoder2`) and the odometry (node `odometry`, 50 Hz, `encoder1..3` →
//! `odometry` for the gateway).
#![no_std]
#![no_main]

use triskar2_firmware as fw;

#[rtic::app(device = rtcan_board_stm32f103::hal::pac, dispatchers = [EXTI2, EXTI3, EXTI4])]
mod app {
    use super::fw;
    use fw::driver::Driver;
    use fw::robot::motor2 as module;
    use module::nodes::{motor_ctrl2, odometry};
    use rtcan_board_stm32f103::filter_set;

    type Drv = Driver<{ module::RX_COUNT }, { module::ARENA_BYTES }, { module::QUEUE_CAPACITY }>;

    #[shared]
    struct Shared {
        drv: Drv,
    }

    #[local]
    struct Local {
        motor: fw::io::MotorIo,
    }

    #[init]
    fn init(cx: init::Context) -> (Shared, Local) {
        let mut b = fw::board::init(cx.device, filter_set!(module::FILTERS));
        fw::Mono::start(cx.core.SYST, fw::SYSCLK_HZ);
        let motor = fw::io::MotorIo::new(b.tim3, b.tim4, b.pins.pwm, &mut b.pins.b_crl, &mut b.rcc);
        let mut drv = Driver {
            engine: module::engine(b.timer.now()),
            can: b.can,
            timer: b.timer,
            host: module::host(),
        };
        drv.start();
        fw::spawned(motor_ctrl2_task::spawn(), "motor_ctrl2");
        fw::spawned(odometry_task::spawn(), "odometry");
        fw::spawned(supervisor::spawn(), "supervisor");
        defmt::info!("motor2 up");
        (Shared { drv }, Local { motor })
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
    #[task(shared = [drv], local = [motor], priority = 3)]
    async fn motor_ctrl2_task(mut cx: motor_ctrl2_task::Context) {
        fw::tasks::motor_ctrl(
            1,
            &motor_ctrl2::NODE,
            &module::STATUS,
            motor_ctrl2::wheel_setpoints_sub(),
            motor_ctrl2::encoder2_pub(),
            cx.local.motor,
            || cx.shared.drv.lock(|d| d.now()),
        )
        .await
    }

    #[task(shared = [drv], priority = 1)]
    async fn odometry_task(mut cx: odometry_task::Context) {
        fw::tasks::odometry(
            &odometry::NODE,
            &module::STATUS,
            (
                odometry::encoder1_sub(),
                odometry::encoder2_sub(),
                odometry::encoder3_sub(),
            ),
            odometry::odometry_pub(),
            || cx.shared.drv.lock(|d| d.now()),
        )
        .await
    }

    #[task(priority = 1)]
    async fn supervisor(_cx: supervisor::Context) {
        fw::tasks::supervisor(&module::STATUS).await
    }
}
