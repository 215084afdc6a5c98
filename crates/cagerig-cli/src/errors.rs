//! How a failed command reports: one line `error: <context>: <cause>: …` on stderr, each cause
//! once (a cause whose text the previous message already contains is not repeated), or with
//! `--json` an object `{"error": <that line without the prefix>, "causes": [...]}` on stdout,
//! where the command's JSON would have been. Exit status 1 either way.

use std::process::ExitCode;

/// The messages of an error chain, outermost first, without repeats.
pub fn messages(error: &anyhow::Error) -> Vec<String> {
    let mut out: Vec<String> = Vec::new();
    for cause in error.chain() {
        let text = cause.to_string();
        if out.last().is_some_and(|prev| prev.contains(&text)) {
            continue;
        }
        out.push(text);
    }
    out
}

/// A library warning on stderr, at its level: `note: …` for information (a harmless fact about
/// the input, such as the Arm's weights rounded when written), `warning: …` for the rest.
pub fn report_warning(w: &cagerig::Warning) {
    eprintln!("{}: {w}", w.label());
}

/// Exit status and report of a command's result.
pub fn exit(result: anyhow::Result<()>, json: bool) -> ExitCode {
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            let causes = messages(&e);
            let line = causes.join(": ");
            if json {
                let report = serde_json::json!({ "error": line, "causes": causes });
                println!("{report}");
            } else {
                eprintln!("error: {line}");
            }
            ExitCode::FAILURE
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Debug, thiserror::Error)]
    #[error("step 3: {source}")]
    struct Outer {
        #[source]
        source: std::io::Error,
    }

    #[test]
    fn each_cause_once() {
        let inner = std::io::Error::other("cage vertex 99 is out of range");
        let e = anyhow::Error::new(Outer { source: inner }).context("in edits.json");
        let m = messages(&e);
        assert_eq!(
            m,
            ["in edits.json", "step 3: cage vertex 99 is out of range"]
        );
    }
}
