//! What the studio reports about itself: the lines of the log panel (load warnings, errors of
//! commands, saves and exports) and the frame timings of `--frame-stats`.

use crate::frame_stats::FrameStats;

/// A line of the log panel.
#[derive(Debug, Clone)]
pub struct LogLine {
    pub level: LogLevel,
    pub text: String,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LogLevel {
    Info,
    Warning,
    Error,
}

/// The log panel's lines, oldest first.
#[derive(Debug, Clone, Default)]
pub struct Log {
    lines: Vec<LogLine>,
}

impl Log {
    pub fn info(&mut self, text: impl Into<String>) {
        self.lines.push(LogLine {
            level: LogLevel::Info,
            text: text.into(),
        });
    }

    pub fn warning(&mut self, text: impl Into<String>) {
        self.lines.push(LogLine {
            level: LogLevel::Warning,
            text: text.into(),
        });
    }

    /// An error: logged, and written to stderr.
    pub fn error(&mut self, text: impl Into<String>) {
        let text = text.into();
        eprintln!("cagerig-studio: {text}");
        self.lines.push(LogLine {
            level: LogLevel::Error,
            text,
        });
    }

    /// Lines of `level` logged so far.
    pub fn count(&self, level: LogLevel) -> usize {
        self.lines.iter().filter(|l| l.level == level).count()
    }

    /// Errors logged so far.
    pub fn error_count(&self) -> usize {
        self.count(LogLevel::Error)
    }

    /// The texts of the errors, oldest first.
    pub fn errors(&self) -> impl Iterator<Item = &str> {
        self.lines
            .iter()
            .filter(|l| l.level == LogLevel::Error)
            .map(|l| l.text.as_str())
    }

    pub fn iter(&self) -> std::slice::Iter<'_, LogLine> {
        self.lines.iter()
    }

    pub fn lines(&self) -> &[LogLine] {
        &self.lines
    }
}

impl<'a> IntoIterator for &'a Log {
    type Item = &'a LogLine;
    type IntoIter = std::slice::Iter<'a, LogLine>;

    fn into_iter(self) -> Self::IntoIter {
        self.lines.iter()
    }
}

/// The log and the frame timings, which every edit reports to (a failure is logged, the sync
/// time of a session event is added to the frame's).
#[derive(Debug, Default)]
pub struct Diagnostics {
    pub log: Log,
    pub stats: FrameStats,
}
