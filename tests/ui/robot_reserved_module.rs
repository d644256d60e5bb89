// A module named `topics` clashes with the generated topic constants.
rtcan::robot!("tests/ui/robots/reserved-module.toml");

fn main() {}
