//! Render progress as the command line shows it: a bar with ETA on a
//! terminal (indicatif), plain lines every 10% otherwise (render-farm logs),
//! or nothing. Passes report to it through their progress callback.

use std::io::{IsTerminal, Write};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Mutex;
use std::time::Instant;

use crate::render::PassProgress;

pub enum Progress {
    Silent,
    Bar(indicatif::ProgressBar),
    Lines { label: String, total: AtomicU64, done: AtomicU64, last_decile: Mutex<u64>, start: Mutex<Instant> },
}

impl Progress {
    /// A bar when stderr is a terminal, plain lines otherwise; `quiet` silences both.
    #[must_use]
    pub fn for_stderr(label: &str, quiet: bool) -> Self {
        if quiet {
            Self::Silent
        } else if std::io::stderr().is_terminal() {
            let bar = indicatif::ProgressBar::hidden();
            bar.set_style(
                indicatif::ProgressStyle::with_template(
                    "{prefix} [{bar:40}] {percent:>3}% {elapsed_precise} ETA {eta}",
                )
                .expect("static template")
                .progress_chars("=> "),
            );
            bar.set_prefix(label.to_string());
            Self::Bar(bar)
        } else {
            Self::Lines {
                label: label.to_string(),
                total: AtomicU64::new(0),
                done: AtomicU64::new(0),
                last_decile: Mutex::new(0),
                start: Mutex::new(Instant::now()),
            }
        }
    }

    /// What a pass reports (its progress callback).
    pub fn report(&self, event: PassProgress) {
        match event {
            PassProgress::Started { tiles } => self.start(tiles),
            PassProgress::TileDone => self.advance(),
            PassProgress::Finished => self.finish(),
        }
    }

    fn start(&self, total: u64) {
        match self {
            Self::Silent => {}
            Self::Bar(bar) => {
                bar.set_length(total);
                bar.set_position(0);
                bar.set_draw_target(indicatif::ProgressDrawTarget::stderr());
            }
            Self::Lines { total: t, done, last_decile, start, .. } => {
                t.store(total, Ordering::Relaxed);
                done.store(0, Ordering::Relaxed);
                *last_decile.lock().unwrap_or_else(|e| e.into_inner()) = 0;
                *start.lock().unwrap_or_else(|e| e.into_inner()) = Instant::now();
            }
        }
    }

    fn advance(&self) {
        match self {
            Self::Silent => {}
            Self::Bar(bar) => bar.inc(1),
            Self::Lines { label, total, done, last_decile, start } => {
                let d = done.fetch_add(1, Ordering::Relaxed) + 1;
                let t = total.load(Ordering::Relaxed).max(1);
                let decile = d * 10 / t;
                let mut last = last_decile.lock().unwrap_or_else(|e| e.into_inner());
                if decile > *last {
                    *last = decile;
                    let elapsed = start.lock().unwrap_or_else(|e| e.into_inner()).elapsed().as_secs_f64();
                    let eta = elapsed * (t - d) as f64 / d as f64;
                    let _ = writeln!(
                        std::io::stderr(),
                        "{label}: {:3}% elapsed {elapsed:.1} s, ETA {eta:.1} s",
                        decile * 10
                    );
                }
            }
        }
    }

    fn finish(&self) {
        if let Self::Bar(bar) = self {
            bar.finish_and_clear();
        }
    }
}
