//! Interrupt glue: what each RTIC hardware task does, as functions over the engine, the
//! adapter, the timer and the host, so the app only locks and calls.
use crate::can::{BxCan, ErrorChange};
use crate::slot_timer::SlotTimer;
use rtcan_core::driver::Host;
use rtcan_core::engine::Engine;

/// Slot timer interrupt (TIM2): when the alarm is due, runs the engine until its next
/// wake-up lies in the future and arms it. Also checks the bus-off state once per slot.
pub fn on_timer<P, H: Host, const RX: usize, const A: usize, const Q: usize>(
    timer: &mut SlotTimer,
    can: &mut BxCan<P>,
    engine: &mut Engine<'_, RX, A, Q>,
    host: &mut H,
) {
    if !timer.on_interrupt() {
        return;
    }
    if can.check_errors() == ErrorChange::BusOff {
        engine.on_bus_off();
    }
    poll(timer, can, engine, host);
}

/// Runs `Engine::poll` and arms the alarm at its answer (again while that is already due).
pub fn poll<P, H: Host, const RX: usize, const A: usize, const Q: usize>(
    timer: &mut SlotTimer,
    can: &mut BxCan<P>,
    engine: &mut Engine<'_, RX, A, Q>,
    host: &mut H,
) {
    loop {
        let next = engine.poll(timer.now(), can, host);
        if timer.set_alarm(next) {
            break;
        }
    }
}

/// CAN RX FIFO 0 interrupt (USB_LP_CAN_RX0).
pub fn on_rx<P, H: Host, const RX: usize, const A: usize, const Q: usize>(
    timer: &SlotTimer,
    can: &mut BxCan<P>,
    engine: &mut Engine<'_, RX, A, Q>,
    host: &mut H,
) {
    let now = timer.now();
    while let Some((frame, sof)) = can.receive(now) {
        engine.on_rx(&frame, sof, can, host);
    }
    if can.take_overrun() {
        engine.on_rx_overrun();
    }
}

/// CAN TX mailbox interrupt (USB_HP_CAN_TX).
pub fn on_tx<P, H: Host, const RX: usize, const A: usize, const Q: usize>(
    timer: &SlotTimer,
    can: &mut BxCan<P>,
    engine: &mut Engine<'_, RX, A, Q>,
    host: &mut H,
) {
    while let Some((mailbox, result)) = can.tx_completion() {
        engine.on_tx_done(mailbox, result, timer.now(), can, host);
    }
}

/// CAN status-change interrupt (CAN_SCE): error counters, bus-off entry and recovery.
pub fn on_sce<P, const RX: usize, const A: usize, const Q: usize>(
    can: &mut BxCan<P>,
    engine: &mut Engine<'_, RX, A, Q>,
) {
    if can.check_errors() == ErrorChange::BusOff {
        engine.on_bus_off();
    }
}
