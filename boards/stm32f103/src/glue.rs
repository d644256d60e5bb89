//! Interrupt glue: what each RTIC hardware task does, as functions over the engine, the
//! adapter, the timer and the host, so the app only locks and calls.
use crate::can::BxCan;
use crate::slot_timer::SlotTimer;
use rtcan_core::confinement::ErrorState;
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
    report_errors(timer, can, engine, host);
    poll(timer, can, engine, host);
}

/// Reads the controller's error state and hands it to the engine when it changed
/// (`Engine::on_error_state`: error-passive counted, bus-off stops the module until the
/// hardware recovery, then it rejoins after re-synchronising).
fn report_errors<P, H: Host, const RX: usize, const A: usize, const Q: usize>(
    timer: &SlotTimer,
    can: &mut BxCan<P>,
    engine: &mut Engine<'_, RX, A, Q>,
    host: &mut H,
) {
    can.check_errors();
    let state = ErrorState {
        tec: u16::from(can.stats().tec),
        rec: u16::from(can.stats().rec),
        bus_off: can.is_bus_off(),
    };
    if state != engine.error_state() {
        engine.on_error_state(timer.now(), state, can, host);
    }
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
pub fn on_sce<P, H: Host, const RX: usize, const A: usize, const Q: usize>(
    timer: &SlotTimer,
    can: &mut BxCan<P>,
    engine: &mut Engine<'_, RX, A, Q>,
    host: &mut H,
) {
    report_errors(timer, can, engine, host);
}
