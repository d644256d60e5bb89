//! Interrupt bodies of the split architecture (boards/common `protocol`) on the F103, so
//! the RTIC app only locks and calls.
use crate::can::CanTx;
use crate::slot_timer::SlotTimer;
use rtcan_board_common::protocol::SlotCore;

/// The slot-timer resource of the F103: TIM2, the plan, the TX mailboxes.
pub type Core<P> = SlotCore<SlotTimer, CanTx<P>>;

/// TIM2 interrupt (highest priority): flag work, then the prepared plan's TXRQ stores
/// and aborts. True when the protocol task must run (plan committed or prepare alarm).
pub fn on_slot_timer<P>(core: &mut Core<P>) -> bool {
    let f = core.timer.flags();
    // The boundary's TXRQ first: the flag bookkeeping can wait until it is stored.
    let committed = f.commit && core.on_commit();
    core.timer.acknowledge(f);
    committed || f.prepare
}
