//! Node lifecycle: Init → Run → Stop / Fail, with the safety rule applied by `update`.
use core::cell::Cell;

use critical_section::Mutex;

use crate::status::SystemStatus;

/// State of a node; the byte value is what the module's heartbeat carries.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[repr(u8)]
pub enum NodeState {
    /// Not started yet (waiting for the bus, calibrating).
    Init = 0,
    /// Running.
    Run = 1,
    /// Stopped, by request or because the system required the safe state.
    Stop = 2,
    /// Failed; only `reset` leaves it.
    Fail = 3,
}

impl NodeState {
    /// Heartbeat byte.
    pub const fn as_u8(self) -> u8 {
        self as u8
    }
    /// From a heartbeat byte.
    pub const fn from_u8(b: u8) -> Option<Self> {
        match b {
            0 => Some(NodeState::Init),
            1 => Some(NodeState::Run),
            2 => Some(NodeState::Stop),
            3 => Some(NodeState::Fail),
            _ => None,
        }
    }
}

/// A software node (R2P §3.4.2). `static` friendly: `static PID: Node = Node::new("pid");`
pub struct Node {
    name: &'static str,
    state: Mutex<Cell<(NodeState, bool)>>,
}

impl Node {
    /// A node in `Init`.
    pub const fn new(name: &'static str) -> Self {
        Node {
            name,
            state: Mutex::new(Cell::new((NodeState::Init, false))),
        }
    }

    /// Name (unique within the module).
    pub fn name(&self) -> &'static str {
        self.name
    }

    /// Current state.
    pub fn state(&self) -> NodeState {
        critical_section::with(|cs| self.state.borrow(cs).get().0)
    }

    /// Whether the last stop was forced by the safe-state rule.
    pub fn safe_stopped(&self) -> bool {
        critical_section::with(|cs| self.state.borrow(cs).get().1)
    }

    fn set(&self, s: NodeState, safe: bool) {
        critical_section::with(|cs| self.state.borrow(cs).set((s, safe)));
    }

    /// Init/Stop → Run, unless the system requires the safe state. `false` if refused
    /// (safe state required, or the node failed).
    pub fn start(&self, status: &SystemStatus) -> bool {
        if self.state() == NodeState::Fail || status.safe_state_required() {
            return false;
        }
        self.set(NodeState::Run, false);
        true
    }

    /// → Stop (by request).
    pub fn stop(&self) {
        if self.state() != NodeState::Fail {
            self.set(NodeState::Stop, false);
        }
    }

    /// → Fail.
    pub fn fail(&self) {
        self.set(NodeState::Fail, false);
    }

    /// Fail → Init.
    pub fn reset(&self) {
        self.set(NodeState::Init, false);
    }

    /// Applies the safety rule: a running node stops when the system requires the
    /// safe state. It stays stopped until started again (a motor must not restart
    /// by itself when the bus comes back). Returns the state after the rule.
    pub fn update(&self, status: &SystemStatus) -> NodeState {
        let s = self.state();
        if s == NodeState::Run && status.safe_state_required() {
            self.set(NodeState::Stop, true);
            return NodeState::Stop;
        }
        s
    }

    /// `update(status) == Run`: the loop condition of a node (R2P's `node.run()`).
    pub fn run(&self, status: &SystemStatus) -> bool {
        self.update(status) == NodeState::Run
    }
}

/// State a module announces: the worst of its nodes (Fail > Init > Stop > Run), `Run`
/// for a module without nodes.
pub fn module_state(nodes: &[&Node]) -> NodeState {
    let mut worst = NodeState::Run;
    for n in nodes {
        let s = n.state();
        let rank = |s: NodeState| match s {
            NodeState::Run => 0,
            NodeState::Stop => 1,
            NodeState::Init => 2,
            NodeState::Fail => 3,
        };
        if rank(s) > rank(worst) {
            worst = s;
        }
    }
    worst
}
