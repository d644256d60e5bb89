//! Writes the hostile robot files of issue 9 to stdout, for the figures in README.md and
//! docs/ROBOT_TOML.md:
//!
//! ```text
//! cargo run --release -p rtcan-model --example hostile -- errors48k > /tmp/e48k.toml
//! cargo build --release -p rtcan-cli && time target/release/rtcan check /tmp/e48k.toml
//! ```
//!
//! Kinds: `errors48k` (48 000 unknown keys, 5 MB), `refs64k` (64 000 topics published
//! by 64 000 nodes), `misspelled8k` (8 000 misspelled node references against 8 000
//! nodes), `big50` (50 MB of valid topics), `hrt12` / `hrt96` (robots/hrt200.toml with
//! the period of `t004` changed from 64 to 12 / 96 slots).
use std::io::Write;

const HEADER: &str = "[bus]\ncycle = \"10ms\"\nslots = 20\nmaster = \"m\"\n\n[types.T]\nv = \"u8\"\n\n[modules.m]\nboard = \"qemu\"\n";

fn main() -> std::io::Result<()> {
    let kind = std::env::args().nth(1).unwrap_or_default();
    let mut s = String::new();
    match kind.as_str() {
        "errors48k" => {
            s += HEADER;
            s += "\n[nodes.n]\nmodule = \"m\"\n";
            for i in 0..48_000 {
                s += &format!("\n[topics.t{i}]\ntype = \"T\"\npublisher = \"n\"\nclass = \"nrt\"\nbogus_key_{i} = \"{}\"\n", "x".repeat(25));
            }
        }
        "refs64k" => {
            s += HEADER;
            for i in 0..64_000 {
                s += &format!("[nodes.n{i}]\nmodule = \"m\"\n");
            }
            for i in 0..64_000 {
                s += &format!(
                    "[topics.t{i}]\ntype = \"T\"\npublisher = \"n{i}\"\nclass = \"nrt\"\n"
                );
            }
        }
        "misspelled8k" => {
            s += HEADER;
            for i in 0..8_000 {
                s += &format!("[nodes.node_number_{i}]\nmodule = \"m\"\n");
            }
            for i in 0..8_000 {
                s += &format!("[topics.t{i}]\ntype = \"T\"\npublisher = \"nod_number_x{i}\"\nclass = \"nrt\"\n");
            }
        }
        "big50" => {
            s += HEADER;
            s += "[nodes.n]\nmodule = \"m\"\n";
            let mut i = 0;
            while s.len() < 50_000_000 {
                s += &format!("[topics.t{i}]\ntype = \"T\"\npublisher = \"n\"\nclass = \"nrt\"\nsubscribers = [\"n\"]\n\n");
                i += 1;
            }
        }
        "hrt12" | "hrt96" => {
            let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../robots/hrt200.toml");
            let from = "[topics.t004]\ntype = \"T\"\npublisher = \"n4\"\nclass = \"hrt\"\nperiod_slots = 64\n";
            let to = from.replace("= 64", if kind == "hrt12" { "= 12" } else { "= 96" });
            s = std::fs::read_to_string(path)?.replace(from, &to);
        }
        _ => {
            eprintln!("usage: hostile errors48k|refs64k|misspelled8k|big50|hrt12|hrt96");
            std::process::exit(2);
        }
    }
    std::io::stdout().lock().write_all(s.as_bytes())
}
