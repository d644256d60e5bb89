//! The engine with everything it drives, as one RTIC resource shared by the hardware
//! tasks (slot timer, CAN RX0/TX/SCE, kick). All of them run at the same, highest
//! priority, so they never preempt each other and RTIC grants them the resource
//! without a lock; the module's app task only locks it briefly to read the clock.
use rtcan_board_stm32f103::glue;
use rtcan_board_stm32f103::hal::gpio::Floating;
use rtcan_board_stm32f103::hal::pac::{Interrupt, NVIC};
use rtcan_board_stm32f103::{BxCan, SlotTimer};
use rtcan_core::engine::Engine;
use rtcan_core::time::Nanos;
use rtcan_pubsub::ModuleHost;

use crate::board::Bus;
use crate::run::DELIVERED;

/// Interrupt of the kick task (unused by the F103's peripherals in these images).
pub const KICK_INTERRUPT: Interrupt = Interrupt::EXTI1;

/// The app published: pend the kick task, which hands SRT/NRT messages to the engine
/// (the generated topics of `rtcan::robot_toml` have no kick hook of their own).
pub fn kick() {
    NVIC::pend(KICK_INTERRUPT);
}

/// Engine, CAN adapter, slot timer and the module's topics as the engine's host.
pub struct Driver<const RX: usize, const ARENA: usize, const Q: usize> {
    engine: Engine<'static, RX, ARENA, Q>,
    can: BxCan<Floating>,
    timer: SlotTimer,
    host: ModuleHost<'static>,
}

impl<const RX: usize, const ARENA: usize, const Q: usize> Driver<RX, ARENA, Q> {
    /// The driver over the module's generated engine and host.
    pub fn new(engine: Engine<'static, RX, ARENA, Q>, bus: Bus, host: ModuleHost<'static>) -> Self {
        Driver {
            engine,
            can: bus.can,
            timer: bus.timer,
            host,
        }
    }

    /// Local time, ns (the clock of the engine and of received messages' stamps).
    pub fn now(&self) -> Nanos {
        self.timer.now()
    }

    /// First run of the engine after start-up: arms the slot alarm.
    pub fn start(&mut self) {
        glue::poll(
            &mut self.timer,
            &mut self.can,
            &mut self.engine,
            &mut self.host,
        );
    }

    /// TIM2: slot boundaries, window ends, bus-off check.
    pub fn on_timer(&mut self) {
        glue::on_timer(
            &mut self.timer,
            &mut self.can,
            &mut self.engine,
            &mut self.host,
        );
        // A boundary frees queue room and may open a window: hand over what waits.
        if self.pump() {
            self.rearm();
        }
    }

    /// USB_LP_CAN_RX0: received frames (reassembly, delivery to local subscribers).
    /// A delivery wakes the app at once (event-driven nodes: obstacle_avoid on
    /// teleop, the gateway forwarding reports), as the simulator runs it after one.
    pub fn on_rx(&mut self) {
        let delivered = self.engine.counters().rx_delivered;
        glue::on_rx(&self.timer, &mut self.can, &mut self.engine, &mut self.host);
        self.rearm();
        if self.engine.counters().rx_delivered != delivered {
            DELIVERED.notify();
        }
    }

    /// USB_HP_CAN_TX: mailbox completions (the next frame is loaded from here).
    pub fn on_tx(&mut self) {
        glue::on_tx(&self.timer, &mut self.can, &mut self.engine, &mut self.host);
        // A completion frees queue room and may end a transfer early.
        self.pump();
        self.rearm();
    }

    /// CAN_SCE: error counters, bus-off.
    pub fn on_sce(&mut self) {
        glue::on_sce(&self.timer, &mut self.can, &mut self.engine, &mut self.host);
    }

    /// Kick: SRT/NRT messages published by node tasks go to the engine.
    pub fn on_kick(&mut self) {
        if self.pump() {
            self.rearm();
        }
    }

    /// Hands queued SRT/NRT messages to the engine; true if any was submitted.
    fn pump(&mut self) -> bool {
        let now = self.timer.now();
        self.host.pump(&mut self.engine, now, &mut self.can) > 0
    }

    /// The engine's next wake-up may have moved (a submit, a sync frame): re-arm.
    fn rearm(&mut self) {
        glue::poll(
            &mut self.timer,
            &mut self.can,
            &mut self.engine,
            &mut self.host,
        );
    }
}
