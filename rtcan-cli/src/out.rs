//! Writing to stdout/stderr without panicking: `print!` panics when the reader went away
//! (`rtcan check robot.toml | head -1` closes the pipe: "failed printing to stdout:
//! Broken pipe", exit 101). Here a closed pipe means "nobody wants the rest": the
//! write stops quietly and the command keeps its own exit code.
use std::io::{self, Write};

/// Outcome of a write: `false` once the reader has gone away (stop producing output).
pub type Open = bool;

fn write_to(mut w: impl Write, text: &str) -> Open {
    match w.write_all(text.as_bytes()).and_then(|()| w.flush()) {
        Ok(()) => true,
        // A closed pipe is the reader's choice; any other error (disk full on a
        // redirect) is also not worth a panic, but it is worth a note on stderr.
        Err(e) if e.kind() == io::ErrorKind::BrokenPipe => false,
        Err(e) => {
            let _ = writeln!(io::stderr(), "error: cannot write output: {e}");
            false
        }
    }
}

/// `print!` that stops quietly on a closed pipe.
pub fn print(text: &str) -> Open {
    write_to(io::stdout().lock(), text)
}

/// `println!` that stops quietly on a closed pipe.
pub fn println(text: &str) -> Open {
    print(text) && print("\n")
}

/// `eprint!` that stops quietly on a closed pipe.
pub fn eprint(text: &str) -> Open {
    write_to(io::stderr().lock(), text)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A writer whose reader has gone away.
    struct Closed;
    impl Write for Closed {
        fn write(&mut self, _: &[u8]) -> io::Result<usize> {
            Err(io::Error::from(io::ErrorKind::BrokenPipe))
        }
        fn flush(&mut self) -> io::Result<()> {
            Ok(())
        }
    }

    #[test]
    fn closed_pipe_is_reported_not_panicked() {
        assert!(!write_to(Closed, "x"));
        assert!(write_to(Vec::new(), "x"));
    }
}
