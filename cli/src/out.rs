//! What the commands print. Standard output may be a pipe that closes
//! early (`ppmc run | head`): then printing stops quietly, and a long
//! command is asked to stop as on SIGINT, instead of panicking. Verdict
//! words are coloured on a terminal unless `NO_COLOR` is set or `--color
//! never` is given.

use std::fmt;
use std::io::{self, IsTerminal, Write};
use std::sync::atomic::{AtomicBool, Ordering};

static STDOUT_CLOSED: AtomicBool = AtomicBool::new(false);
static COLOR: AtomicBool = AtomicBool::new(false);
static TO_STDERR: AtomicBool = AtomicBool::new(false);

/// Sends the lines meant for people to standard error, because standard
/// output carries a report (`--junit -`).
pub fn people_to_stderr() {
    TO_STDERR.store(true, Ordering::Relaxed);
}

/// When to colour the verdict words.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, clap::ValueEnum)]
pub enum ColorChoice {
    /// On a terminal, unless `NO_COLOR` is set.
    #[default]
    Auto,
    Always,
    Never,
}

/// Decides once, at start-up, whether verdicts are coloured.
pub fn set_color(choice: ColorChoice) {
    let on = match choice {
        ColorChoice::Always => true,
        ColorChoice::Never => false,
        ColorChoice::Auto => {
            io::stdout().is_terminal() && std::env::var_os("NO_COLOR").is_none_or(|v| v.is_empty())
        }
    };
    COLOR.store(on, Ordering::Relaxed);
}

/// Writes one line to standard output; nothing once it has closed.
pub fn line(args: fmt::Arguments<'_>) {
    if TO_STDERR.load(Ordering::Relaxed) {
        return error_line(args);
    }
    if STDOUT_CLOSED.load(Ordering::Relaxed) {
        return;
    }
    let mut out = io::stdout().lock();
    let done = out
        .write_fmt(args)
        .and_then(|()| out.write_all(b"\n"))
        .and_then(|()| out.flush());
    if done.is_err() {
        // A closed pipe or a vanished terminal: nobody reads any more.
        STDOUT_CLOSED.store(true, Ordering::Relaxed);
    }
}

/// Writes one line to standard error, ignoring a closed stream.
pub fn error_line(args: fmt::Arguments<'_>) {
    let mut err = io::stderr().lock();
    let _ = err.write_fmt(args).and_then(|()| err.write_all(b"\n"));
}

/// Whether standard output has closed under us.
pub fn stdout_closed() -> bool {
    STDOUT_CLOSED.load(Ordering::Relaxed)
}

/// A verdict word, padded to `width`, coloured when colour is on.
pub fn verdict_word(word: &str, width: usize) -> String {
    let padded = format!("{word:<width$}");
    if !COLOR.load(Ordering::Relaxed) {
        return padded;
    }
    let code = match word {
        "PASS" | "SAME" => "32", // green
        "MARGINAL" => "33",      // yellow
        "FAIL" => "1;31",        // bold red
        "ERROR" => "1;35",       // bold magenta
        _ => "2",                // dim: not run
    };
    format!("\x1b[{code}m{word}\x1b[0m{}", &padded[word.len()..])
}

/// `println!` that a closed pipe ends quietly.
macro_rules! outln {
    () => { $crate::out::line(format_args!("")) };
    ($($arg:tt)*) => { $crate::out::line(format_args!($($arg)*)) };
}

/// `eprintln!` that never panics.
macro_rules! errln {
    ($($arg:tt)*) => { $crate::out::error_line(format_args!($($arg)*)) };
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn verdict_words_are_padded_and_coloured_only_when_asked() {
        set_color(ColorChoice::Never);
        assert_eq!(verdict_word("FAIL", 8), "FAIL    ");
        set_color(ColorChoice::Always);
        assert_eq!(verdict_word("FAIL", 8), "\x1b[1;31mFAIL\x1b[0m    ");
        set_color(ColorChoice::Never);
    }
}
