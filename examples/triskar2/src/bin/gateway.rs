//! Module `gateway`: the bus master and the host link (node `ros_bridge`). The host
//! (ROS) talks over USART1 at 115 200 Bd through a USB-serial adapter: on the F103 the
//! USB and CAN peripherals share their packet SRAM and cannot run together, so the
//! on-chip USB is not an option while RTCAN runs. Frames: `triskar2_link`.
//! Host → robot: `teleop` (SRT to obstacle_avoid); robot → host: `odometry`,
//! `proximity`, `battery`, `log`.
#![no_std]
#![no_main]

use triskar2_firmware as fw;

#[rtic::app(device = rtcan_board_stm32f103::hal::pac, dispatchers = [EXTI2, EXTI3, EXTI4])]
mod app {
    use super::fw;
    use fw::driver::Driver;
    use fw::robot::gateway as module;
    use fw::robot::Twist;
    use module::nodes::ros_bridge;
    use rtcan_board_stm32f103::filter_set;
    use rtcan_board_stm32f103::hal::pac::USART1;
    use rtcan_board_stm32f103::hal::prelude::*;
    use rtcan_board_stm32f103::hal::serial::{Config, Rx, SerialExt, Tx};
    use rtcan_pubsub::Message;
    use triskar2_link::{topic, Decoder};

    type Drv = Driver<{ module::RX_COUNT }, { module::ARENA_BYTES }, { module::QUEUE_CAPACITY }>;

    #[shared]
    struct Shared {
        drv: Drv,
    }

    #[local]
    struct Local {
        link_tx: Tx<USART1>,
        link_rx: Rx<USART1>,
        decoder: Decoder,
    }

    #[init]
    fn init(cx: init::Context) -> (Shared, Local) {
        let mut b = fw::board::init(cx.device, filter_set!(module::FILTERS));
        fw::Mono::start(cx.core.SYST, fw::SYSCLK_HZ);
        let (pa9, pa10) = b.pins.usart1;
        let tx_pin = pa9.into_alternate_push_pull(&mut b.pins.a_crh);
        let serial = b
            .usart1
            .serial::<_, rtcan_board_stm32f103::hal::gpio::Floating>(
                (tx_pin, pa10),
                Config::default().baudrate(115_200.bps()),
                &mut b.rcc,
            );
        let (link_tx, mut link_rx) = serial.split();
        link_rx.listen();
        let mut drv = Driver {
            engine: module::engine(b.timer.now()),
            can: b.can,
            timer: b.timer,
            host: module::host(),
        };
        drv.start();
        fw::spawned(ros_bridge_task::spawn(), "ros_bridge");
        fw::spawned(supervisor::spawn(), "supervisor");
        defmt::info!("gateway up (bus master)");
        (
            Shared { drv },
            Local {
                link_tx,
                link_rx,
                decoder: Decoder::new(),
            },
        )
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
    /// Host → robot: bytes from the link; a checked `teleop` frame is published (SRT,
    /// 20 ms deadline) stamped with the local clock.
    #[task(binds = USART1, shared = [drv], local = [link_rx, decoder], priority = 2)]
    fn link_rx(mut cx: link_rx::Context) {
        while let Ok(byte) = cx.local.link_rx.read() {
            let Some((t, payload)) = cx.local.decoder.push(byte) else {
                continue;
            };
            if t != topic::TELEOP {
                continue;
            }
            match Twist::decode(payload) {
                Some(twist) => {
                    let now = cx.shared.drv.lock(|d| d.now());
                    if ros_bridge::teleop_pub().send(twist, now).is_err() {
                        defmt::warn!("teleop dropped: pool exhausted");
                    }
                }
                None => defmt::warn!("teleop frame of {} bytes", payload.len()),
            }
        }
    }

    #[task(local = [link_tx], priority = 1)]
    async fn ros_bridge_task(cx: ros_bridge_task::Context) {
        let tx = cx.local.link_tx;
        fw::tasks::ros_bridge(
            &ros_bridge::NODE,
            &module::STATUS,
            ros_bridge::odometry_sub(),
            ros_bridge::proximity_sub(),
            ros_bridge::battery_sub(),
            ros_bridge::log_sub(),
            |bytes| {
                for &byte in bytes {
                    // Blocking at 115 200 Bd (87 µs a byte) in the lowest-priority task.
                    let _ = nb::block!(tx.write_u8(byte));
                }
            },
        )
        .await
    }

    #[task(priority = 1)]
    async fn supervisor(_cx: supervisor::Context) {
        fw::tasks::supervisor(&module::STATUS).await
    }
}
