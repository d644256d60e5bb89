//! The robot of /robot.toml, generated at compile time by `rtcan::robot!`: message
//! types (`Twist`, `WheelSpeeds`, ...), and per module (`gateway`, `motor1`, ...) the
//! engine tables, acceptance filters, engine sizes, topic statics with their pools,
//! typed publisher/subscriber handles per node and the `ModuleHost` glue. A robot.toml
//! that is invalid or not admissible on the bus stops the build with its diagnostics.
//! SRT/NRT publishes pend the kick task (`driver::kick`), which hands them to the engine.
rtcan::robot!("../../robot.toml", kick = crate::driver::kick);
