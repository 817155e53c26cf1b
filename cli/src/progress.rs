//! Progress of a run: a bar on a terminal, plain lines otherwise.

use indicatif::{ProgressBar, ProgressStyle};
use std::io::IsTerminal;

/// Progress on a terminal, plain lines otherwise.
pub struct Progress {
    bar: Option<ProgressBar>,
}

impl Progress {
    pub fn new(total: usize) -> Progress {
        let bar = std::io::stderr().is_terminal().then(|| {
            let b = ProgressBar::new(total as u64);
            if let Ok(style) = ProgressStyle::with_template("{bar:40} {pos}/{len} {msg}") {
                b.set_style(style);
            }
            b
        });
        Progress { bar }
    }

    pub fn line(&self, text: &str) {
        match &self.bar {
            // The bar is on standard error; the line goes to standard
            // output, as without a terminal.
            Some(b) => b.suspend(|| outln!("{text}")),
            None => outln!("{text}"),
        }
    }

    pub fn step(&self, name: &str) {
        if let Some(b) = &self.bar {
            b.inc(1);
            b.set_message(name.to_string());
        }
    }

    pub fn finish(&self) {
        if let Some(b) = &self.bar {
            b.finish_and_clear();
        }
    }
}
