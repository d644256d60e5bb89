//! The `rtcan` command. One file per subcommand, each with its `clap` arguments (`Args`)
//! and `run(Args) -> i32`; this file only lists them and dispatches. A new subcommand is
//! a `mod` line, a variant of [`Cmd`] and an arm of [`dispatch`].
use clap::{CommandFactory, FromArgMatches, Parser, Subcommand};

mod bridge;
mod call;
mod check;
mod decode;
mod echo;
mod emulate;
mod flash;
mod link_args;
mod log_epoch;
mod module_table;
mod monitor;
mod monitor_tui;
mod new;
mod out;
mod param;
mod pub_;
mod record;
mod sim;

/// Every help page starts with its usage line, as before clap (scripts grep for it).
const TEMPLATE: &str = "usage: {usage}\n\n{about-with-newline}\n{all-args}{after-help}";

#[derive(Parser)]
#[command(
    name = "rtcan",
    version,
    about = "RTCAN robots from robot.toml: check, simulate, decode, watch and bridge a bus",
    help_template = TEMPLATE,
    subcommand_required = true,
    arg_required_else_help = true
)]
struct Cli {
    #[command(subcommand)]
    cmd: Cmd,
}

#[derive(Subcommand)]
enum Cmd {
    /// Validate, admit and plan a robot; print the plan
    ///
    /// The plan for a person, or JSON with --json (docs/ROBOT_TOML.md). Exit 0
    /// admissible, 1 not admissible, 2 invalid input, 3 undecided (admission search
    /// budget exhausted).
    Check(check::Args),
    /// Simulate the robot on a bit-accurate bus (docs/SIM.md)
    ///
    /// The workspace robot runs triskar2, any other robot its generic traffic scenario.
    /// --emulate runs the Triskar2 release images on emulated STM32F103s instead
    /// (options --seconds, --seed, --cpi, --json, --images; docs/EMULATOR.md);
    /// --campaign runs the fault campaign on triskar2 and rtcan-paper, N s per case
    /// (default 10).
    Sim(Box<sim::Args>),
    /// candump log -> topic-level messages
    ///
    /// Remote, error and CAN FD frames are skipped and counted; malformed lines are
    /// reported (first 10) and counted. Exit 0 when every line parsed, 1 otherwise, 2 on
    /// usage errors.
    Decode(decode::Args),
    /// Print a topic's messages as they arrive
    ///
    /// One line per message, or with --json one object per line:
    /// {"time":SECONDS,"topic":NAME,"value":{FIELDS}}.
    Echo(echo::Args),
    /// Publish a value from the host
    ///
    /// JSON is an object with every field of TOPIC's type, e.g.
    /// rtcan pub teleop '{"vx":0.3,"vy":0,"wz":0}'; a value that does not fit its
    /// field's type is refused (exit 2). Then watches the bus for --seconds (default 1)
    /// and says how many messages carried the value.
    Pub(pub_::Args),
    /// Write the bus to a candump log
    ///
    /// Every frame of the bus to FILE (`-`: standard output) in `candump -l` format,
    /// simulated frames stamped from a real epoch; --count counts frames here.
    Record(record::Args),
    /// Modules, topics and bus load of a running bus
    ///
    /// On a terminal, a live screen redrawn every --every seconds until q, Esc or
    /// Ctrl-C (into a pipe, the plain table); --once runs the bus for --seconds (default
    /// 2) and prints the table once, --once --screen the screen as text.
    Monitor(monitor::Args),
    /// Every topic on Zenoh under rtcan/<robot>/<topic> (docs/BRIDGE.md)
    ///
    /// Runs until --seconds or Ctrl-C, then prints what it did. Every message is put on
    /// rtcan/<robot>/<topic> (JSON objects; --raw: the little-endian payload); samples
    /// on the topics robot.toml marks writable are published on the bus, others refused
    /// and counted. <robot> is --robot-name or robot.toml's `[robot] name` (default: its
    /// file stem). --ros2: the topics robot.toml maps to ROS 2 types as rmw_zenoh puts
    /// them (node /<robot>/rtcan_bridge, CDR, liveliness tokens), through a Zenoh router
    /// (--connect, default tcp/127.0.0.1:7447).
    Bridge(bridge::Args),
    /// Module parameters, range-checked by the module (docs/SERVICES.md)
    ///
    /// Requests go over the simulated robot's bus (--sim) to the parameter server of
    /// the module; exit 1 when a module refuses a value or does not answer.
    Param(param::Args),
    /// Firmware update over the bus (docs/SERVICES.md §4)
    ///
    /// Against the simulated robot (--sim, the default): host -> gateway link -> bus ->
    /// module, with the robot's HRT and SRT traffic running. Prints per module the bytes,
    /// request frames, simulated bus time, retries and the result. Exit 0 every update
    /// committed, 1 one failed, 2 bad input.
    Flash(flash::Args),
    /// One request/reply call of a robot.toml service (docs/SERVICES.md)
    ///
    /// On the simulated robot (--sim, the default; its node code is compiled from the
    /// workspace robot), e.g. rtcan call proximity_read '{"sensor":2}'. Prints the reply
    /// (--json: service, call, request, reply or null, outcome, latency_ns). Exit 0
    /// replied, 1 timed out or refused, 2 bad input.
    Call(call::Args),
    /// A firmware workspace for a robot (docs/SCAFFOLD.md)
    ///
    /// Writes into DIR one image per module, one node file per node, the host-side
    /// simulator entry and size budgets; re-running adds what is new and never
    /// overwrites node sources. Exit 0 written, 2 invalid robot, usage or I/O error.
    New(new::Args),
}

fn dispatch(cmd: Cmd) -> i32 {
    match cmd {
        Cmd::Check(a) => check::run(a),
        Cmd::Sim(a) => sim::run(*a),
        Cmd::Decode(a) => decode::run(a),
        Cmd::Echo(a) => echo::run(a),
        Cmd::Pub(a) => pub_::run(a),
        Cmd::Record(a) => record::run(a),
        Cmd::Monitor(a) => monitor::run(a),
        Cmd::Bridge(a) => bridge::run(a),
        Cmd::Param(a) => param::run(a),
        Cmd::Flash(a) => flash::run(a),
        Cmd::Call(a) => call::run(a),
        Cmd::New(a) => new::run(a),
    }
}

/// The command line's grammar, with what only the running program knows (the simulator's
/// built-in scenarios) added to the help pages.
fn command() -> clap::Command {
    Cli::command()
        .mut_subcommands(|c| c.help_template(TEMPLATE))
        .mut_subcommand("sim", |c| {
            c.after_help(format!(
                "built-in scenarios:\n{}",
                rtcan_sim::session::built_in_list()
            ))
        })
}

fn main() {
    // clap prints help/version (exit 0) and usage errors (exit 2) itself.
    let matches = command().get_matches();
    let cli = match Cli::from_arg_matches(&matches) {
        Ok(c) => c,
        Err(e) => e.exit(),
    };
    std::process::exit(dispatch(cli.cmd));
}

/// Reports a usage error found after parsing (a combination clap cannot express) the way
/// clap reports its own: message, the subcommand's usage, exit code 2.
fn usage_error(sub: &str, what: &str) -> i32 {
    let mut cmd = command();
    cmd.build();
    let usage = cmd
        .find_subcommand_mut(sub)
        .map(|c| c.render_usage().to_string())
        .unwrap_or_default();
    eprintln!("error: {what}\n\n{usage}\n\nFor more information, try '--help'.");
    2
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::panic, clippy::indexing_slicing)]
mod tests {
    use super::*;

    #[test]
    fn the_grammar_is_consistent() {
        command().debug_assert();
    }
}
