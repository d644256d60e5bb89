//! Module `motor1`: DC motor 1 (node `motor_ctrl1`, 200 Hz PID, publishes `encoder1`)
//! and the inverse kinematics (node `kinematics`, 100 Hz, `velocity` →
//! `wheel_setpoints` for all three motors).
#![no_std]
#![no_main]

use triskar2_firmware as fw;

#[rtic::app(device = rtcan_board_stm32f103::hal::pac, dispatchers = [EXTI2, EXTI3, EXTI4])]
mod app {
    use super::fw;
    use fw::driver::Driver;
    use fw::robot::motor1 as module;
    use module::nodes::{kinematics, motor_ctrl1};
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
        fw::spawned(motor_ctrl1_task::spawn(), "motor_ctrl1");
        fw::spawned(kinematics_task::spawn(), "kinematics");
        fw::spawned(supervisor::spawn(), "supervisor");
        defmt::info!("motor1 up");
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
    async fn motor_ctrl1_task(mut cx: motor_ctrl1_task::Context) {
        fw::tasks::motor_ctrl(
            0,
            &motor_ctrl1::NODE,
            &module::STATUS,
            motor_ctrl1::wheel_setpoints_sub(),
            motor_ctrl1::encoder1_pub(),
            cx.local.motor,
            || cx.shared.drv.lock(|d| d.now()),
        )
        .await
    }

    #[task(shared = [drv], priority = 2)]
    async fn kinematics_task(mut cx: kinematics_task::Context) {
        fw::tasks::kinematics(
            &kinematics::NODE,
            &module::STATUS,
            kinematics::velocity_sub(),
            kinematics::wheel_setpoints_pub(),
            || cx.shared.drv.lock(|d| d.now()),
        )
        .await
    }

    #[task(priority = 1)]
    async fn supervisor(_cx: supervisor::Context) {
        fw::tasks::supervisor(&module::STATUS).await
    }
}
