//! The `rtcan` command. One file per subcommand; this file only dispatches.
mod bridge;
mod check;
mod decode;
mod echo;
mod emulate;
mod link_args;
mod monitor;
mod new;
mod out;
mod param;
mod pub_;
mod record;
mod sim;

const USAGE: &str = "\
usage: rtcan <command> [args]

commands:
  check <robot.toml> [--json]   validate, admit and plan a robot; print the plan
                                exit 0 admissible, 1 not admissible, 2 invalid input,
                                3 undecided (admission search budget exhausted)
  sim [robot.toml] [--scenario rtcan-paper|triskar2|file.toml] [--seconds N] [--seed S]
      [--load X] [--ber P] [--json] [--out DIR] [--sweep] [--master-dies-at S]
                                simulate the robot on a bit-accurate bus (docs/SIM.md;
                                `rtcan sim --help`)
  decode <log|-> (--robot robot.toml | --scenario rtcan-paper) [--force]
                                candump log -> topic-level messages (`rtcan decode --help`)
  echo TOPIC [--json]           print a topic's messages as they arrive (`rtcan echo --help`)
  pub TOPIC JSON                publish a value from the host (`rtcan pub --help`)
  record FILE                   write the bus to a candump log (`rtcan record --help`)
  monitor [--once]              modules, topics and bus load (`rtcan monitor --help`)
                                these four take the bus as --sim robot.toml (default),
                                --replay LOG, --serial PORT or --can IFACE
  bridge [--listen E] [--connect E]   every topic on Zenoh, rtcan/<robot>/<topic>
                                (`rtcan bridge --help`, docs/BRIDGE.md)
  param (list | get <node.name> | set <node.name> <value>) [--sim robot.toml] [--json]
                                module parameters, range-checked by the module
                                (docs/SERVICES.md); exit 1 when refused
  new <DIR> [--robot robot.toml]
                                write a firmware workspace for the robot: one image per
                                module, one file per node, `cargo run -p sim`; re-running
                                adds what is new, never overwrites node files; exit 2
                                invalid robot (`rtcan new --help`)
  help                          this text
";

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    std::process::exit(run(&args));
}

/// Runs a subcommand and returns the exit code.
fn run(args: &[String]) -> i32 {
    let (cmd, rest) = match args.split_first() {
        Some((c, r)) => (c.as_str(), r),
        None => {
            eprint!("{USAGE}");
            return 2;
        }
    };
    match cmd {
        "check" => check::run(rest),
        "sim" => sim::run(rest),
        "decode" => decode::run(rest),
        "echo" => echo::run(rest),
        "pub" => pub_::run(rest),
        "record" => record::run(rest),
        "monitor" => monitor::run(rest),
        "new" => new::run(rest),
        "bridge" => bridge::run(rest),
        "--version" | "-V" => {
            println!("rtcan {}", env!("CARGO_PKG_VERSION"));
            0
        }
        "param" => param::run(rest),
        "help" | "-h" | "--help" => {
            print!("{USAGE}");
            0
        }
        other => {
            eprintln!("error: unknown command `{other}`\n");
            eprint!("{USAGE}");
            2
        }
    }
}

/// Reports a usage error with the subcommand's usage; exit code 2.
fn usage_error(what: &str, usage: &str) -> i32 {
    eprintln!("error: {what}\n\n{usage}");
    2
}
