//! One module per node of robot.toml: the node's task as the generated module apps
//! (`crate::app`, laid out by build.rs from robot.toml's placement) run it. Each has
//! `Task`, `const fn new() -> Task`, `Hw` (the hardware the node needs) and
//! `poll(&mut Task, now, &mut impl Hw) -> next due`, and reaches its topics through
//! `rtcan::robot_toml::nodes::<node>`, which follows the node to whatever module
//! robot.toml puts it on: no task names its module.

pub mod battery_monitor;
pub mod ir_ranger;
pub mod kinematics;
pub mod motor_ctrl;
pub mod obstacle_avoid;
pub mod odometry;
pub mod ros_bridge;

pub use motor_ctrl::{motor_ctrl1, motor_ctrl2, motor_ctrl3};

/// The hardware of a node that needs none: every module's hardware has it.
pub trait NoHw {}

impl<T: ?Sized> NoHw for T {}
