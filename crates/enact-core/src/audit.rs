//! The audit log's vocabulary: who acts ([`Actor`]), what they did ([`AuditAction`]) and the
//! entry as stored and shown ([`AuditEntry`]). Writing and reading entries is
//! `enact_hub::app::audit`'s.

use std::fmt;

use serde::Serialize;

/// Who did something.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Actor {
    /// The account behind an API token.
    Account(String),
    /// An annotator (or admin) in a browser session.
    Annotator(String),
    /// Someone at the command line, named by `$USER` (or `operator`).
    Operator(String),
    /// The service itself, e.g. loading the demo dataset at start.
    Server,
}

impl Actor {
    pub fn kind(&self) -> &'static str {
        match self {
            Actor::Account(_) => "account",
            Actor::Annotator(_) => "annotator",
            Actor::Operator(_) => "operator",
            Actor::Server => "server",
        }
    }

    pub fn name(&self) -> &str {
        match self {
            Actor::Account(name) | Actor::Annotator(name) | Actor::Operator(name) => name,
            Actor::Server => "enact-hub",
        }
    }

    /// The inverse of ([`Actor::kind`], [`Actor::name`]).
    pub fn from_parts(kind: &str, name: &str) -> Option<Actor> {
        match kind {
            "account" => Some(Actor::Account(name.to_owned())),
            "annotator" => Some(Actor::Annotator(name.to_owned())),
            "operator" => Some(Actor::Operator(name.to_owned())),
            "server" => Some(Actor::Server),
            _ => None,
        }
    }
}

impl fmt::Display for Actor {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} {}", self.kind(), self.name())
    }
}

/// What was done. The stored names are `noun.verb`, so a filter on the noun is a prefix.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum AuditAction {
    DatasetImport,
    /// A stratified subset of a dataset stored as a dataset of its own.
    DatasetSubset,
    DatasetAnswerVisibility,
    TokenIssue,
    TokenRevoke,
    SubmissionCreate,
    SubmissionListing,
    BaselineFile,
    AnnotatorCreate,
    AnnotatorActivate,
    AssignmentChange,
    ProtocolRun,
    AnnotationAnswer,
    AnnotationSkip,
    BackupCreate,
    StudyCreate,
    StudyDelete,
    JobPause,
    JobResume,
    JobCancel,
    /// Stored results computed again under the current metric version.
    MetricRescore,
    RunStart,
    /// A dataset's gold set chosen (or replaced), with its rate.
    GoldSet,
    GoldClear,
    /// An annotator's answers kept out of a dataset's Human row and agreement report.
    AnnotatorExclude,
    AnnotatorInclude,
    /// A real-world episode's frames imported.
    EpisodeImport,
    /// A curator's key frames and graphs of an episode set (replacing the earlier ones).
    EpisodeGraphs,
    /// The graphs an episode exports chosen by an admin.
    EpisodeResolve,
    /// Results a paper published attached to a dataset (an import or one row).
    ReportedAdd,
    ReportedRemove,
    /// A model's category, family, size or link on a dataset set.
    ModelMetadata,
    /// The hub's statement-signing key made (on first start) or replaced by a new one.
    KeyGenerate,
    KeyRotate,
    /// A hidden dataset's items drawn into a public and a private part.
    DatasetSplit,
    /// A split dataset's private part revealed (at its deadline or by hand).
    DatasetReveal,
    /// A challenge's deadline or selection limit set.
    ChallengeSettings,
    /// A submission selected for (or withdrawn from) a challenge's final ranking.
    SubmissionSelect,
    /// An import whose items or frames also belong to a public dataset.
    DatasetLeak,
    /// An annotator's queue paused: they can read it but not work on it, and get no new items.
    AnnotatorPause,
    AnnotatorResume,
    /// An annotator's unfinished items split over other annotators.
    AnnotatorHandover,
    /// A dataset's attention checks chosen (or replaced), with their rate.
    AttentionSet,
    AttentionClear,
}

impl AuditAction {
    pub const ALL: [AuditAction; 44] = [
        AuditAction::DatasetImport,
        AuditAction::DatasetSubset,
        AuditAction::DatasetAnswerVisibility,
        AuditAction::TokenIssue,
        AuditAction::TokenRevoke,
        AuditAction::SubmissionCreate,
        AuditAction::SubmissionListing,
        AuditAction::BaselineFile,
        AuditAction::AnnotatorCreate,
        AuditAction::AnnotatorActivate,
        AuditAction::AssignmentChange,
        AuditAction::ProtocolRun,
        AuditAction::AnnotationAnswer,
        AuditAction::AnnotationSkip,
        AuditAction::BackupCreate,
        AuditAction::StudyCreate,
        AuditAction::StudyDelete,
        AuditAction::JobPause,
        AuditAction::JobResume,
        AuditAction::JobCancel,
        AuditAction::MetricRescore,
        AuditAction::RunStart,
        AuditAction::GoldSet,
        AuditAction::GoldClear,
        AuditAction::AnnotatorExclude,
        AuditAction::AnnotatorInclude,
        AuditAction::EpisodeImport,
        AuditAction::EpisodeGraphs,
        AuditAction::EpisodeResolve,
        AuditAction::ReportedAdd,
        AuditAction::ReportedRemove,
        AuditAction::ModelMetadata,
        AuditAction::KeyGenerate,
        AuditAction::KeyRotate,
        AuditAction::DatasetSplit,
        AuditAction::DatasetReveal,
        AuditAction::ChallengeSettings,
        AuditAction::SubmissionSelect,
        AuditAction::DatasetLeak,
        AuditAction::AnnotatorPause,
        AuditAction::AnnotatorResume,
        AuditAction::AnnotatorHandover,
        AuditAction::AttentionSet,
        AuditAction::AttentionClear,
    ];

    pub fn as_str(self) -> &'static str {
        match self {
            AuditAction::DatasetImport => "dataset.import",
            AuditAction::DatasetSubset => "dataset.subset",
            AuditAction::DatasetAnswerVisibility => "dataset.answer_visibility",
            AuditAction::TokenIssue => "token.issue",
            AuditAction::TokenRevoke => "token.revoke",
            AuditAction::SubmissionCreate => "submission.create",
            AuditAction::SubmissionListing => "submission.listing",
            AuditAction::BaselineFile => "submission.baseline",
            AuditAction::AnnotatorCreate => "annotator.create",
            AuditAction::AnnotatorActivate => "annotator.activate",
            AuditAction::AssignmentChange => "assignment.change",
            AuditAction::ProtocolRun => "protocol.run",
            AuditAction::AnnotationAnswer => "annotation.answer",
            AuditAction::AnnotationSkip => "annotation.skip",
            AuditAction::BackupCreate => "backup.create",
            AuditAction::StudyCreate => "study.create",
            AuditAction::StudyDelete => "study.delete",
            AuditAction::JobPause => "job.pause",
            AuditAction::JobResume => "job.resume",
            AuditAction::JobCancel => "job.cancel",
            AuditAction::MetricRescore => "metric.rescore",
            AuditAction::RunStart => "run.start",
            AuditAction::GoldSet => "gold.set",
            AuditAction::GoldClear => "gold.clear",
            AuditAction::AnnotatorExclude => "annotator.exclude",
            AuditAction::AnnotatorInclude => "annotator.include",
            AuditAction::EpisodeImport => "episode.import",
            AuditAction::EpisodeGraphs => "episode.graphs",
            AuditAction::EpisodeResolve => "episode.resolve",
            AuditAction::ReportedAdd => "reported.add",
            AuditAction::ReportedRemove => "reported.remove",
            AuditAction::ModelMetadata => "model.metadata",
            AuditAction::KeyGenerate => "key.generate",
            AuditAction::KeyRotate => "key.rotate",
            AuditAction::DatasetSplit => "dataset.split",
            AuditAction::DatasetReveal => "dataset.reveal",
            AuditAction::ChallengeSettings => "challenge.settings",
            AuditAction::SubmissionSelect => "submission.select",
            AuditAction::DatasetLeak => "dataset.leak",
            AuditAction::AnnotatorPause => "annotator.pause",
            AuditAction::AnnotatorResume => "annotator.resume",
            AuditAction::AnnotatorHandover => "annotator.handover",
            AuditAction::AttentionSet => "attention.set",
            AuditAction::AttentionClear => "attention.clear",
        }
    }

    pub fn parse(text: &str) -> Option<AuditAction> {
        AuditAction::ALL.into_iter().find(|a| a.as_str() == text)
    }
}

/// An entry about to be written: the action on `target` (in words: "token ab12cd",
/// "submission 42", "item kitchen_…"), with the dataset it concerns and a short detail.
#[derive(Debug, Clone)]
pub struct AuditRecord<'a> {
    pub actor: &'a Actor,
    pub action: AuditAction,
    pub target: String,
    pub dataset: Option<&'a str>,
    pub detail: String,
}

/// An entry as stored. `action` is kept as text so entries written by a newer version still read.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct AuditEntry {
    pub id: i64,
    pub at: String,
    pub actor_kind: String,
    pub actor: String,
    pub action: String,
    pub target: String,
    pub dataset: Option<String>,
    pub detail: String,
}

/// Which entries to show; every field left empty matches everything.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct AuditFilter {
    /// An action name, or its noun alone (`token` matches `token.issue` and `token.revoke`).
    pub action: Option<String>,
    pub actor: Option<String>,
    pub dataset: Option<String>,
    /// Entries at or after this UTC time (`2026-11-25` or `2026-11-25T10:00:00Z`).
    pub since: Option<String>,
    /// Entries older than this id (the next page of a newest-first listing).
    pub before_id: Option<i64>,
    pub limit: usize,
}

impl AuditFilter {
    /// Checks the filter's values, naming the field that is wrong.
    pub fn checked(self) -> Result<AuditFilter, String> {
        if let Some(action) = &self.action {
            let known = AuditAction::ALL
                .iter()
                .any(|a| a.as_str() == action || a.as_str().split('.').next() == Some(action));
            if !known {
                let names: Vec<&str> = AuditAction::ALL.iter().map(|a| a.as_str()).collect();
                return Err(format!(
                    "`action`: unknown action {action:?}; one of {} (or the part before the dot)",
                    names.join(", ")
                ));
            }
        }
        let mut filter = self;
        if let Some(since) = &filter.since {
            filter.since = Some(comparable_time(since).ok_or_else(|| {
                format!(
                    "`since`: {since:?} is not a UTC date or time (2026-11-25 or \
                     2026-11-25T10:00:00Z)"
                )
            })?);
        }
        if filter.limit == 0 || filter.limit > 10_000 {
            return Err(format!("`limit` must be 1..10000, not {}", filter.limit));
        }
        Ok(filter)
    }
}

/// `YYYY-MM-DD`, optionally followed by `THH:MM[:SS[.fff]]Z`, written so that it compares as
/// text with the stored times (`2026-11-25T10:00:00.000Z`): seconds filled in, no final `Z`.
fn comparable_time(text: &str) -> Option<String> {
    if !is_utc_time(text) {
        return None;
    }
    let Some(clock) = text.get(11..).and_then(|t| t.strip_suffix('Z')) else {
        return Some(text.to_owned());
    };
    let seconds = if clock.len() == 5 { ":00" } else { "" };
    Some(format!("{}T{clock}{seconds}", &text[..10]))
}

fn is_utc_time(text: &str) -> bool {
    let bytes = text.as_bytes();
    let digits = |range: std::ops::Range<usize>| {
        bytes
            .get(range)
            .is_some_and(|b| b.iter().all(u8::is_ascii_digit))
    };
    let date = bytes.len() >= 10
        && digits(0..4)
        && bytes[4] == b'-'
        && digits(5..7)
        && bytes[7] == b'-'
        && digits(8..10);
    if !date {
        return false;
    }
    let time = &text[10..];
    if time.is_empty() {
        return true;
    }
    let Some(clock) = time.strip_prefix('T').and_then(|t| t.strip_suffix('Z')) else {
        return false;
    };
    let (hms, fraction) = clock.split_once('.').unwrap_or((clock, "0"));
    let parts: Vec<&str> = hms.split(':').collect();
    (parts.len() == 2 || parts.len() == 3)
        && parts
            .iter()
            .all(|p| p.len() == 2 && p.bytes().all(|b| b.is_ascii_digit()))
        && !fraction.is_empty()
        && fraction.bytes().all(|b| b.is_ascii_digit())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn action_names_read_back() {
        for action in AuditAction::ALL {
            assert_eq!(AuditAction::parse(action.as_str()), Some(action));
        }
        assert_eq!(AuditAction::parse("token"), None);
    }

    #[test]
    fn actors_read_back_from_their_parts() {
        for actor in [
            Actor::Account("team".into()),
            Actor::Annotator("ana".into()),
            Actor::Operator("root".into()),
            Actor::Server,
        ] {
            assert_eq!(Actor::from_parts(actor.kind(), actor.name()), Some(actor));
        }
        assert_eq!(Actor::from_parts("robot", "r1"), None);
    }

    #[test]
    fn filters_name_the_wrong_field() {
        let filter = |action: Option<&str>, since: Option<&str>, limit| AuditFilter {
            action: action.map(str::to_owned),
            since: since.map(str::to_owned),
            limit,
            ..AuditFilter::default()
        };
        assert!(filter(Some("token"), None, 50).checked().is_ok());
        assert!(
            filter(Some("token.issue"), Some("2026-11-25"), 50)
                .checked()
                .is_ok()
        );
        assert!(
            filter(None, Some("2026-11-25T10:00Z"), 50)
                .checked()
                .is_ok()
        );
        assert!(
            filter(None, Some("2026-11-25T10:00:01.5Z"), 50)
                .checked()
                .is_ok()
        );
        let e = filter(Some("tokens"), None, 50).checked().unwrap_err();
        assert!(e.starts_with("`action`"), "{e}");
        for bad in [
            "yesterday",
            "2026-11-25 10:00",
            "2026-11-25T10Z",
            "2026-1-25",
        ] {
            let e = filter(None, Some(bad), 50).checked().unwrap_err();
            assert!(e.starts_with("`since`"), "{bad}: {e}");
        }
        assert!(
            filter(None, None, 0)
                .checked()
                .unwrap_err()
                .starts_with("`limit`")
        );
        // What is kept compares with the stored `2026-11-25T10:00:00.000Z` as text.
        let since = |text| {
            filter(None, Some(text), 50)
                .checked()
                .unwrap()
                .since
                .unwrap()
        };
        assert_eq!(since("2026-11-25"), "2026-11-25");
        assert_eq!(since("2026-11-25T10:00Z"), "2026-11-25T10:00:00");
        assert_eq!(since("2026-11-25T10:00:01.5Z"), "2026-11-25T10:00:01.5");
        assert!("2026-11-25T10:00:00.000Z" >= since("2026-11-25T10:00Z").as_str());
    }
}
