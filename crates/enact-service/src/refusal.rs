//! Why a request was refused, as data: which item, which field, which limit. A [`Refusal`] is
//! put into words only at the edge that shows it:
//! - the web's pages say it in the request's language, from the catalogues' `refusal-*`
//!   messages (`web::error`);
//! - the JSON API answers with its stable [`Refusal::code`] and its [`Refusal::details`],
//!   beside the English sentence ([`std::fmt::Display`]);
//! - the command line prints the English sentence, with its own flags where a flag helps.
//!
//! The English sentences name no command-line flag: a page or an API client cannot use one.
//! Refusals not yet given a variant here are still `AppError`'s sentence variants, answered
//! with their kind's code (`not_found`, `invalid`, ...).

use std::fmt;

use crate::core::annotation::DraftProblem;

/// What kind of refusal it is: the web answers each kind with one status code.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RefusalKind {
    NotFound,
    Invalid,
    Unauthenticated,
    NotPermitted,
    Conflict,
    /// A quota is used up: 429, with `Retry-After` when waiting helps
    /// ([`Refusal::retry_after`]).
    LimitReached,
}

/// Skipping an item or flagging it: both finish it without an answer, with a reason.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SkipAction {
    Skip,
    Flag,
}

impl SkipAction {
    pub fn as_str(self) -> &'static str {
        match self {
            SkipAction::Skip => "skip",
            SkipAction::Flag => "flag",
        }
    }
}

/// What is wrong with the path of a release an admin asks the server to import from its
/// import folder.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ImportPathProblem {
    /// Empty or absolute: it must be relative to the import folder.
    NotRelative,
    /// Nothing is at that path in the import folder.
    Missing,
    /// It leaves the import folder (`..`, or a symbolic link out).
    LeavesFolder,
    /// Neither a release folder nor a `.jsonl` file.
    NotARelease,
    /// The release's images' folder lies outside the import folder.
    ReleaseLeavesFolder,
}

/// A value a refusal names, for the sentence made from it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Detail {
    Text(String),
    Number(u64),
    /// A moment, as the store keeps it (ISO 8601 in UTC: `2026-11-29T12:00:00Z`), which each
    /// edge writes as its readers do.
    Time(String),
}

impl From<&Detail> for serde_json::Value {
    fn from(d: &Detail) -> Self {
        match d {
            Detail::Text(t) | Detail::Time(t) => serde_json::Value::from(t.as_str()),
            Detail::Number(n) => serde_json::Value::from(*n),
        }
    }
}

/// What a field's value must be, for [`Refusal::BadValue`].
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Expected {
    /// A whole number from `least` to `most`.
    WholeNumber { least: u64, most: u64 },
    /// A whole number of `least` or more.
    WholeNumberFrom { least: u64 },
    /// A number, with a fraction if need be.
    Number,
    /// A number from `least` to `most`, with a fraction if need be (a percentage).
    NumberBetween { least: u64, most: u64 },
    /// A number above 0 and below 1: a share, or a confidence level.
    Fraction,
    /// One of these words.
    OneOf(Vec<&'static str>),
    /// A name of 1 to `most` letters, digits, `_` or `-` (it names a folder).
    PlainName { most: u64 },
    /// A submission's id.
    SubmissionId,
    /// A reported result's id.
    ReportedId,
}

impl fmt::Display for Expected {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Expected::WholeNumber { least, most } => {
                write!(f, "a whole number from {least} to {most}")
            }
            Expected::WholeNumberFrom { least } => write!(f, "a whole number of {least} or more"),
            Expected::Number => write!(f, "a number"),
            Expected::NumberBetween { least, most } => {
                write!(f, "a number from {least} to {most}")
            }
            Expected::Fraction => write!(f, "a number above 0 and below 1"),
            Expected::OneOf(words) => write!(f, "one of: {}", words.join(", ")),
            Expected::PlainName { most } => {
                write!(f, "a name of 1 to {most} letters, digits, '_' or '-'")
            }
            Expected::SubmissionId => write!(f, "a submission's id"),
            Expected::ReportedId => write!(f, "a reported result's id"),
        }
    }
}

/// A refusal with its reason typed. Each variant has a stable [`code`](Refusal::code), the
/// API's promise to clients; renaming one is a breaking change.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Refusal {
    /// No dataset has this name (or the caller may not see it).
    NoDataset { dataset: String },
    /// The dataset has no item with this id.
    NoItem { dataset: String, item: String },
    /// No annotator has this login name.
    NoAnnotator { annotator: String },
    /// No episode has this name.
    NoEpisode { episode: String },
    /// No submission has this id (or it is another account's).
    NoSubmission { submission: String },
    /// No model run has this id or name.
    NoRun { run: String },
    /// No frame has this SHA-256.
    NoFrame { frame: String },
    /// The annotator has not finished this item yet, so there is no answer of theirs to show.
    NoAnswerYet { item: String },
    /// A login link that is unknown or was used already (a link is good once).
    LoginLinkUsed,
    /// A request that needs a login session came without a live one.
    NotLoggedIn,
    /// An annotator asked for an admin page.
    AdminOnly { annotator: String },
    /// A state-changing request without the page's CSRF token, or with a stale one.
    StaleForm,
    /// The item exists but is not in this annotator's queue.
    NotAssigned { dataset: String, item: String },
    /// The item is finished: its answer, skip or flag can no longer change.
    ItemFinished { item: String },
    /// An admin paused this annotator's queue at `since`.
    QueuePaused { since: String },
    /// An answer with empty slots (1-based).
    SlotsEmpty { item: String, slots: Vec<usize> },
    /// A draft or answer whose slots do not fit the item; each problem has its own code.
    DraftInvalid { item: String, problem: DraftProblem },
    /// A skip or flag without a reason.
    ReasonMissing { item: String, action: SkipAction },
    /// A skip or flag reason over `limit` characters.
    ReasonTooLong { limit: u64 },
    /// The new password and its repetition differ.
    PasswordsDiffer,
    /// The new password has `chars` characters, fewer than `least`.
    PasswordTooShort { chars: u64, least: u64 },
    /// An export of an episode whose scene graphs no curator has set.
    EpisodeHasNoGraphs { episode: String },
    /// A model run's price (`field`: `price_input` or `price_output`, in US dollars per
    /// million tokens) below 0 or not a number.
    RunPrice { field: String, price: String },
    /// This server imports from its own disk only when its operator names an import folder.
    ImportFolderUnset,
    /// A study of this name exists already.
    StudyExists { study: String },
    /// No dataset has the name given as a new study's baseline.
    StudyBaselineMissing { dataset: String },
    /// No dataset has the name given for a new study's variant (`family/label`).
    StudyVariantMissing { variant: String, dataset: String },
    /// None of a variant's items aligns with the baseline's (by id, or by task, type and key
    /// frames).
    StudyVariantUnaligned {
        variant: String,
        dataset: String,
        items: u64,
        baseline: String,
        baseline_items: u64,
    },
    /// The path of a release to import from the import folder does not name one inside it.
    ImportPath {
        path: String,
        problem: ImportPathProblem,
    },
    /// A challenge's request on a dataset not split into a public and a private part.
    ChallengeNotSplit { dataset: String },
    /// The private part was revealed (at its deadline, or by hand) at `at`: the final ranking,
    /// its settings and its selections are fixed.
    ChallengeRevealed {
        dataset: String,
        at_deadline: bool,
        at: String,
    },
    /// A dataset whose answers are public cannot be split: every submitter can score any part.
    ChallengeAnswersPublic { dataset: String },
    /// A split needs two items at least.
    ChallengeTooFewItems { dataset: String, items: u64 },
    /// A split is final.
    ChallengeAlreadySplit {
        dataset: String,
        at: String,
        by: String,
        seed: u64,
        public_share: String,
    },
    /// Only a published submission can be selected for the final ranking.
    SelectionNotPublished {
        submission: String,
        visibility: String,
    },
    /// The account has selected as many submissions as the challenge allows.
    SelectionLimitReached {
        dataset: String,
        limit: u64,
        account: String,
        selected: String,
    },
    /// The private part's figures are for admins until it is revealed (at `reveal_at`, when
    /// one is set).
    PrivatePartHidden {
        dataset: String,
        reveal_at: Option<String>,
    },
    /// No study has this name.
    NoStudy { study: String },
    /// No live API token has this id or prefix.
    NoToken { token: String },
    /// No background job has this id.
    NoJob { job: String },
    /// The dataset has no reported result (a paper's published figure) with this id.
    NoReported { dataset: String, reported: String },
    /// This curator stored no scene graphs for the episode.
    NoCuratorGraphs { episode: String, curator: String },
    /// The dataset's answers are hidden, so nothing that shows them is shown.
    AnswersHidden { dataset: String },
    /// An invite link that is unknown or was used already.
    InviteLinkUsed,
    /// No submission of this model on the dataset.
    NoModelSubmission { dataset: String, model: String },
    /// A row to compare (`field`) names a submission id that is not published on the dataset.
    NoPublishedSubmission {
        field: String,
        dataset: String,
        submission: String,
    },
    /// A row to compare (`field`) names a model with no published row on the dataset; `models`
    /// lists those that have one.
    NoPublishedModel {
        field: String,
        dataset: String,
        model: String,
        models: String,
    },
    /// The dataset's paper folder has no file of this name; `files` lists what it has.
    NoPaperFile {
        dataset: String,
        file: String,
        files: String,
    },
    /// No route of the API has this path.
    NoApiRoute { path: String },
    /// An API request without a bearer token.
    TokenMissing,
    /// An `Authorization` header that is not `Bearer TOKEN`.
    AuthorizationMalformed,
    /// A bearer token that is unknown or revoked.
    TokenUnknown,
    /// The token is live but lacks the scope this request needs.
    ScopeMissing { scope: &'static str },
    /// A model's metadata is set by the account that submitted it, or by an admin.
    NotModelOwner { dataset: String, model: String },
    /// The token has made its `limit` submissions for today (UTC); the day turns in
    /// `retry_after` seconds.
    DailyQuotaUsed { limit: u64, retry_after: u64 },
    /// The token's total quota is used up: `used` of `limit`. Waiting does not help.
    TotalQuotaUsed { used: u64, limit: u64 },
    /// An `Idempotency-Key` used before, for `submission`, with another body.
    IdempotencyKeyReused { submission: String },
    /// An episode of this name exists already.
    EpisodeExists { episode: String },
    /// Another import holds the episode's name since `since` (by `by`); its claim lapses in
    /// `lapses_in` seconds unless it writes again.
    EpisodeImporting {
        episode: String,
        since: String,
        by: String,
        lapses_in: u64,
    },
    /// This import wrote nothing for over `after` seconds and another import of the name took
    /// it over.
    EpisodeTakenOver { episode: String, after: u64 },
    /// Several curators stored graphs of the episode and none are chosen for its export.
    EpisodeNotResolved { episode: String, curators: String },
    /// An export needs `least` key frames; the episode's graphs mark `key_frames`.
    TooFewKeyFrames {
        episode: String,
        key_frames: u64,
        least: u64,
    },
    /// A comparison of curators needs two; the episode has graphs from `curators`.
    TooFewCurators { episode: String, curators: u64 },
    /// A curator chosen for a frame marked no key frame there.
    NoKeyFrame {
        episode: String,
        curator: String,
        frame: u64,
    },
    /// An uploaded frame whose file name cannot order it.
    FrameNameUnusable { name: String },
    /// A list (`field`) that must name one thing at least names none.
    EmptyList { field: &'static str },
    /// A list (`field`) names an item twice.
    ListedTwice { field: &'static str, item: String },
    /// A list (`field`) of gold items or attention checks names every item of the dataset:
    /// the Human row would be left with none.
    LeavesNoItems {
        field: &'static str,
        dataset: String,
    },
    /// A dataset of fewer than two items cannot have gold items.
    TooFewForGold { dataset: String, items: u64 },
    /// An item cannot be both a gold item and an attention check; `field` is the list that
    /// names it, `items` those it names that are already the other.
    GoldAndAttention {
        field: &'static str,
        dataset: String,
        items: String,
    },
    /// Every annotator chosen for a split has a paused queue.
    AllChosenPaused,
    /// A handover's recipient has a paused queue.
    RecipientPaused { annotator: String },
    /// An annotator cannot hand their items over to themselves.
    HandoverToSelf { annotator: String },
    /// No other active annotator with a running queue can take a handover.
    NoRecipient { annotator: String },
    /// A dataset of this name exists already.
    DatasetExists { dataset: String },
    /// A request without fields it needs.
    FieldsRequired { fields: Vec<&'static str> },
    /// A request must give exactly one of these fields: it gave none, or more than one.
    ExactlyOneOf { fields: Vec<&'static str> },
    /// Two fields that go together: a request gave one without the other.
    BothOrNeither { fields: [&'static str; 2] },
    /// A field that cannot be given together with `other`.
    NotWith {
        field: &'static str,
        other: &'static str,
    },
    /// A field, form field or query parameter whose value is not what it must be.
    BadValue {
        field: String,
        value: String,
        expected: Expected,
    },
}

impl Refusal {
    /// `field`'s `value` is not what it must be.
    pub fn bad_value(
        field: impl Into<String>,
        value: impl Into<String>,
        expected: Expected,
    ) -> Self {
        Refusal::BadValue {
            field: field.into(),
            value: value.into(),
            expected,
        }
    }

    /// The kind, which chooses the HTTP status.
    pub fn kind(&self) -> RefusalKind {
        match self {
            Refusal::NoDataset { .. }
            | Refusal::NoItem { .. }
            | Refusal::NoAnnotator { .. }
            | Refusal::NoEpisode { .. }
            | Refusal::NoSubmission { .. }
            | Refusal::NoRun { .. }
            | Refusal::NoFrame { .. }
            | Refusal::NoAnswerYet { .. }
            | Refusal::NoStudy { .. }
            | Refusal::NoToken { .. }
            | Refusal::NoJob { .. }
            | Refusal::NoReported { .. }
            | Refusal::NoCuratorGraphs { .. }
            | Refusal::AnswersHidden { .. }
            | Refusal::InviteLinkUsed
            | Refusal::NoModelSubmission { .. }
            | Refusal::NoPublishedSubmission { .. }
            | Refusal::NoPublishedModel { .. }
            | Refusal::NoPaperFile { .. }
            | Refusal::NoApiRoute { .. }
            | Refusal::ImportPath {
                problem: ImportPathProblem::Missing,
                ..
            } => RefusalKind::NotFound,
            Refusal::NotLoggedIn
            | Refusal::TokenMissing
            | Refusal::AuthorizationMalformed
            | Refusal::TokenUnknown => RefusalKind::Unauthenticated,
            Refusal::ScopeMissing { .. } | Refusal::NotModelOwner { .. } => {
                RefusalKind::NotPermitted
            }
            Refusal::EpisodeExists { .. }
            | Refusal::EpisodeImporting { .. }
            | Refusal::EpisodeTakenOver { .. } => RefusalKind::Conflict,
            Refusal::EpisodeNotResolved { .. }
            | Refusal::TooFewKeyFrames { .. }
            | Refusal::TooFewCurators { .. }
            | Refusal::NoKeyFrame { .. }
            | Refusal::FrameNameUnusable { .. } => RefusalKind::Invalid,
            Refusal::DailyQuotaUsed { .. } | Refusal::TotalQuotaUsed { .. } => {
                RefusalKind::LimitReached
            }
            Refusal::IdempotencyKeyReused { .. } => RefusalKind::Conflict,
            Refusal::EmptyList { .. }
            | Refusal::ListedTwice { .. }
            | Refusal::LeavesNoItems { .. }
            | Refusal::TooFewForGold { .. }
            | Refusal::GoldAndAttention { .. }
            | Refusal::HandoverToSelf { .. }
            | Refusal::NoRecipient { .. } => RefusalKind::Invalid,
            Refusal::AllChosenPaused
            | Refusal::RecipientPaused { .. }
            | Refusal::DatasetExists { .. } => RefusalKind::Conflict,
            Refusal::LoginLinkUsed => RefusalKind::NotFound,
            Refusal::AdminOnly { .. }
            | Refusal::StaleForm
            | Refusal::NotAssigned { .. }
            | Refusal::ImportFolderUnset => RefusalKind::NotPermitted,
            Refusal::StudyExists { .. }
            | Refusal::ChallengeNotSplit { .. }
            | Refusal::ChallengeRevealed { .. }
            | Refusal::ChallengeAnswersPublic { .. }
            | Refusal::ChallengeTooFewItems { .. }
            | Refusal::ChallengeAlreadySplit { .. }
            | Refusal::SelectionNotPublished { .. }
            | Refusal::SelectionLimitReached { .. } => RefusalKind::Conflict,
            Refusal::PrivatePartHidden { .. } => RefusalKind::NotPermitted,
            Refusal::StudyBaselineMissing { .. }
            | Refusal::StudyVariantMissing { .. }
            | Refusal::StudyVariantUnaligned { .. } => RefusalKind::Invalid,
            Refusal::ItemFinished { .. } | Refusal::QueuePaused { .. } => RefusalKind::Conflict,
            Refusal::SlotsEmpty { .. }
            | Refusal::DraftInvalid { .. }
            | Refusal::ReasonMissing { .. }
            | Refusal::ReasonTooLong { .. }
            | Refusal::PasswordsDiffer
            | Refusal::PasswordTooShort { .. }
            | Refusal::EpisodeHasNoGraphs { .. }
            | Refusal::RunPrice { .. }
            | Refusal::BadValue { .. }
            | Refusal::FieldsRequired { .. }
            | Refusal::ExactlyOneOf { .. }
            | Refusal::BothOrNeither { .. }
            | Refusal::NotWith { .. }
            | Refusal::ImportPath { .. } => RefusalKind::Invalid,
        }
    }

    /// Seconds after which asking again may succeed, when waiting helps.
    pub fn retry_after(&self) -> Option<u64> {
        match self {
            Refusal::DailyQuotaUsed { retry_after, .. } => Some(*retry_after),
            _ => None,
        }
    }

    /// The stable code a client can branch on: snake case, never reworded.
    pub fn code(&self) -> &'static str {
        match self {
            Refusal::NoDataset { .. } => "no_dataset",
            Refusal::NoItem { .. } => "no_item",
            Refusal::NoAnnotator { .. } => "no_annotator",
            Refusal::NoEpisode { .. } => "no_episode",
            Refusal::NoSubmission { .. } => "no_submission",
            Refusal::NoRun { .. } => "no_run",
            Refusal::NoFrame { .. } => "no_frame",
            Refusal::NoAnswerYet { .. } => "no_answer_yet",
            Refusal::NoStudy { .. } => "no_study",
            Refusal::NoToken { .. } => "no_token",
            Refusal::NoJob { .. } => "no_job",
            Refusal::NoReported { .. } => "no_reported",
            Refusal::NoCuratorGraphs { .. } => "no_curator_graphs",
            Refusal::AnswersHidden { .. } => "answers_hidden",
            Refusal::InviteLinkUsed => "invite_link_used",
            Refusal::NoModelSubmission { .. } => "no_model_submission",
            Refusal::NoPublishedSubmission { .. } => "no_published_submission",
            Refusal::NoPublishedModel { .. } => "no_published_model",
            Refusal::NoPaperFile { .. } => "no_paper_file",
            Refusal::NoApiRoute { .. } => "no_api_route",
            Refusal::NotLoggedIn => "not_logged_in",
            Refusal::LoginLinkUsed => "login_link_used",
            Refusal::AdminOnly { .. } => "admin_only",
            Refusal::StaleForm => "stale_form",
            Refusal::NotAssigned { .. } => "not_assigned",
            Refusal::ItemFinished { .. } => "item_finished",
            Refusal::QueuePaused { .. } => "queue_paused",
            Refusal::SlotsEmpty { .. } => "slots_empty",
            Refusal::DraftInvalid { problem, .. } => match problem {
                DraftProblem::SlotCount { .. } => "draft_slot_count",
                DraftProblem::LabelOutOfRange { .. } => "draft_label_out_of_range",
                DraftProblem::PlacedTwice { .. } => "draft_placed_twice",
                DraftProblem::HistoryTooLong { .. } => "draft_history_too_long",
            },
            Refusal::ReasonMissing { .. } => "reason_missing",
            Refusal::ReasonTooLong { .. } => "reason_too_long",
            Refusal::PasswordsDiffer => "passwords_differ",
            Refusal::PasswordTooShort { .. } => "password_too_short",
            Refusal::EpisodeHasNoGraphs { .. } => "episode_has_no_graphs",
            Refusal::RunPrice { .. } => "run_price",
            Refusal::ImportFolderUnset => "import_folder_unset",
            Refusal::StudyExists { .. } => "study_exists",
            Refusal::StudyBaselineMissing { .. } => "study_baseline_missing",
            Refusal::StudyVariantMissing { .. } => "study_variant_missing",
            Refusal::StudyVariantUnaligned { .. } => "study_variant_unaligned",
            Refusal::ImportPath { problem, .. } => match problem {
                ImportPathProblem::NotRelative => "import_path_not_relative",
                ImportPathProblem::Missing => "import_path_missing",
                ImportPathProblem::LeavesFolder => "import_path_leaves_folder",
                ImportPathProblem::NotARelease => "import_path_not_a_release",
                ImportPathProblem::ReleaseLeavesFolder => "import_release_leaves_folder",
            },
            Refusal::ChallengeNotSplit { .. } => "challenge_not_split",
            Refusal::ChallengeRevealed { .. } => "challenge_revealed",
            Refusal::ChallengeAnswersPublic { .. } => "challenge_answers_public",
            Refusal::ChallengeTooFewItems { .. } => "challenge_too_few_items",
            Refusal::ChallengeAlreadySplit { .. } => "challenge_already_split",
            Refusal::SelectionNotPublished { .. } => "selection_not_published",
            Refusal::SelectionLimitReached { .. } => "selection_limit_reached",
            Refusal::PrivatePartHidden { .. } => "private_part_hidden",
            Refusal::EpisodeExists { .. } => "episode_exists",
            Refusal::EpisodeImporting { .. } => "episode_importing",
            Refusal::EpisodeTakenOver { .. } => "episode_taken_over",
            Refusal::EpisodeNotResolved { .. } => "episode_not_resolved",
            Refusal::TooFewKeyFrames { .. } => "too_few_key_frames",
            Refusal::TooFewCurators { .. } => "too_few_curators",
            Refusal::NoKeyFrame { .. } => "no_key_frame",
            Refusal::FrameNameUnusable { .. } => "frame_name_unusable",
            Refusal::DailyQuotaUsed { .. } => "daily_quota_used",
            Refusal::TotalQuotaUsed { .. } => "total_quota_used",
            Refusal::IdempotencyKeyReused { .. } => "idempotency_key_reused",
            Refusal::EmptyList { .. } => "empty_list",
            Refusal::ListedTwice { .. } => "listed_twice",
            Refusal::LeavesNoItems { .. } => "leaves_no_items",
            Refusal::TooFewForGold { .. } => "too_few_for_gold",
            Refusal::GoldAndAttention { .. } => "gold_and_attention",
            Refusal::AllChosenPaused => "all_chosen_paused",
            Refusal::RecipientPaused { .. } => "recipient_paused",
            Refusal::HandoverToSelf { .. } => "handover_to_self",
            Refusal::NoRecipient { .. } => "no_recipient",
            Refusal::DatasetExists { .. } => "dataset_exists",
            Refusal::TokenMissing => "token_missing",
            Refusal::AuthorizationMalformed => "authorization_malformed",
            Refusal::TokenUnknown => "token_unknown",
            Refusal::ScopeMissing { .. } => "scope_missing",
            Refusal::NotModelOwner { .. } => "not_model_owner",
            Refusal::FieldsRequired { .. } => "fields_required",
            Refusal::ExactlyOneOf { .. } => "exactly_one_of",
            Refusal::BothOrNeither { .. } => "both_or_neither",
            Refusal::NotWith { .. } => "not_with",
            Refusal::BadValue { expected, .. } => match expected {
                Expected::WholeNumber { .. } => "bad_value_whole_number",
                Expected::WholeNumberFrom { .. } => "bad_value_whole_number_from",
                Expected::Number => "bad_value_number",
                Expected::NumberBetween { .. } => "bad_value_number_between",
                Expected::Fraction => "bad_value_fraction",
                Expected::OneOf(_) => "bad_value_one_of",
                Expected::PlainName { .. } => "bad_value_plain_name",
                Expected::SubmissionId => "bad_value_submission_id",
                Expected::ReportedId => "bad_value_reported_id",
            },
        }
    }

    /// The values the refusal names, by the names the catalogues' messages and the API's
    /// `details` use.
    pub fn details(&self) -> Vec<(&'static str, Detail)> {
        let text = |s: &str| Detail::Text(s.to_owned());
        match self {
            Refusal::NoDataset { dataset } => vec![("dataset", text(dataset))],
            Refusal::NoItem { dataset, item } | Refusal::NotAssigned { dataset, item } => {
                vec![("dataset", text(dataset)), ("item", text(item))]
            }
            Refusal::NoAnnotator { annotator } | Refusal::AdminOnly { annotator } => {
                vec![("annotator", text(annotator))]
            }
            Refusal::NoEpisode { episode } | Refusal::EpisodeHasNoGraphs { episode } => {
                vec![("episode", text(episode))]
            }
            Refusal::NoAnswerYet { item } | Refusal::ItemFinished { item } => {
                vec![("item", text(item))]
            }
            Refusal::NoSubmission { submission } => vec![("submission", text(submission))],
            Refusal::NoRun { run } => vec![("run", text(run))],
            Refusal::NoFrame { frame } => vec![("frame", text(frame))],
            Refusal::NoToken { token } => vec![("token", text(token))],
            Refusal::NoJob { job } => vec![("job", text(job))],
            Refusal::NoReported { dataset, reported } => {
                vec![("dataset", text(dataset)), ("reported", text(reported))]
            }
            Refusal::NoCuratorGraphs { episode, curator } => {
                vec![("episode", text(episode)), ("curator", text(curator))]
            }
            Refusal::NoModelSubmission { dataset, model }
            | Refusal::NotModelOwner { dataset, model } => {
                vec![("dataset", text(dataset)), ("model", text(model))]
            }
            Refusal::NoPublishedSubmission {
                field,
                dataset,
                submission,
            } => vec![
                ("field", text(field)),
                ("dataset", text(dataset)),
                ("submission", text(submission)),
            ],
            Refusal::NoPublishedModel {
                field,
                dataset,
                model,
                models,
            } => {
                let mut details = vec![
                    ("field", text(field)),
                    ("dataset", text(dataset)),
                    ("model", text(model)),
                    ("listed", text(if models.is_empty() { "no" } else { "yes" })),
                ];
                if !models.is_empty() {
                    details.push(("models", text(models)));
                }
                details
            }
            Refusal::NoPaperFile {
                dataset,
                file,
                files,
            } => vec![
                ("dataset", text(dataset)),
                ("file", text(file)),
                ("files", text(files)),
            ],
            Refusal::NoApiRoute { path } => vec![("path", text(path))],
            Refusal::ScopeMissing { scope } => vec![("scope", text(scope))],
            Refusal::EpisodeExists { episode } => vec![("episode", text(episode))],
            Refusal::EpisodeImporting {
                episode,
                since,
                by,
                lapses_in,
            } => vec![
                ("episode", text(episode)),
                ("since", Detail::Time(since.clone())),
                ("by", text(by)),
                ("lapses_in", Detail::Number(*lapses_in)),
            ],
            Refusal::EpisodeTakenOver { episode, after } => vec![
                ("episode", text(episode)),
                ("after", Detail::Number(*after)),
            ],
            Refusal::EpisodeNotResolved { episode, curators } => {
                vec![("episode", text(episode)), ("curators", text(curators))]
            }
            Refusal::TooFewKeyFrames {
                episode,
                key_frames,
                least,
            } => vec![
                ("episode", text(episode)),
                ("key_frames", Detail::Number(*key_frames)),
                ("least", Detail::Number(*least)),
            ],
            Refusal::TooFewCurators { episode, curators } => vec![
                ("episode", text(episode)),
                ("curators", Detail::Number(*curators)),
            ],
            Refusal::NoKeyFrame {
                episode,
                curator,
                frame,
            } => vec![
                ("episode", text(episode)),
                ("curator", text(curator)),
                ("frame", Detail::Number(*frame)),
            ],
            Refusal::FrameNameUnusable { name } => vec![("name", text(name))],
            Refusal::DailyQuotaUsed { limit, retry_after } => vec![
                ("limit", Detail::Number(*limit)),
                ("retry_after", Detail::Number(*retry_after)),
            ],
            Refusal::TotalQuotaUsed { used, limit } => vec![
                ("used", Detail::Number(*used)),
                ("limit", Detail::Number(*limit)),
            ],
            Refusal::IdempotencyKeyReused { submission } => {
                vec![("submission", text(submission))]
            }
            Refusal::EmptyList { field } => vec![("field", text(field))],
            Refusal::ListedTwice { field, item } => {
                vec![("field", text(field)), ("item", text(item))]
            }
            Refusal::LeavesNoItems { field, dataset } => {
                vec![("field", text(field)), ("dataset", text(dataset))]
            }
            Refusal::TooFewForGold { dataset, items } => vec![
                ("dataset", text(dataset)),
                ("items", Detail::Number(*items)),
            ],
            Refusal::GoldAndAttention {
                field,
                dataset,
                items,
            } => vec![
                ("field", text(field)),
                ("dataset", text(dataset)),
                ("items", text(items)),
            ],
            Refusal::RecipientPaused { annotator }
            | Refusal::HandoverToSelf { annotator }
            | Refusal::NoRecipient { annotator } => vec![("annotator", text(annotator))],
            Refusal::DatasetExists { dataset } => vec![("dataset", text(dataset))],
            Refusal::TokenMissing
            | Refusal::AuthorizationMalformed
            | Refusal::TokenUnknown
            | Refusal::AllChosenPaused => Vec::new(),
            Refusal::InviteLinkUsed
            | Refusal::NotLoggedIn
            | Refusal::LoginLinkUsed
            | Refusal::StaleForm
            | Refusal::PasswordsDiffer
            | Refusal::ImportFolderUnset => Vec::new(),
            Refusal::ImportPath { path, .. } => vec![("path", text(path))],
            Refusal::StudyExists { study } | Refusal::NoStudy { study } => {
                vec![("study", text(study))]
            }
            Refusal::ChallengeNotSplit { dataset }
            | Refusal::ChallengeAnswersPublic { dataset }
            | Refusal::AnswersHidden { dataset }
            | Refusal::StudyBaselineMissing { dataset } => {
                vec![("dataset", text(dataset))]
            }
            Refusal::ChallengeRevealed {
                dataset,
                at_deadline,
                at,
            } => vec![
                ("dataset", text(dataset)),
                ("how", text(if *at_deadline { "deadline" } else { "hand" })),
                ("at", Detail::Time(at.clone())),
            ],
            Refusal::ChallengeTooFewItems { dataset, items } => {
                vec![
                    ("dataset", text(dataset)),
                    ("items", Detail::Number(*items)),
                ]
            }
            Refusal::ChallengeAlreadySplit {
                dataset,
                at,
                by,
                seed,
                public_share,
            } => vec![
                ("dataset", text(dataset)),
                ("at", Detail::Time(at.clone())),
                ("by", text(by)),
                ("seed", Detail::Number(*seed)),
                ("public_share", text(public_share)),
            ],
            Refusal::SelectionNotPublished {
                submission,
                visibility,
            } => vec![
                ("submission", text(submission)),
                ("visibility", text(visibility)),
            ],
            Refusal::SelectionLimitReached {
                dataset,
                limit,
                account,
                selected,
            } => vec![
                ("dataset", text(dataset)),
                ("limit", Detail::Number(*limit)),
                ("account", text(account)),
                ("selected", text(selected)),
            ],
            Refusal::PrivatePartHidden { dataset, reveal_at } => {
                let mut details = vec![
                    ("dataset", text(dataset)),
                    (
                        "scheduled",
                        text(if reveal_at.is_some() { "yes" } else { "no" }),
                    ),
                ];
                if let Some(at) = reveal_at {
                    details.push(("reveal_at", Detail::Time(at.clone())));
                }
                details
            }
            Refusal::StudyVariantMissing { variant, dataset } => {
                vec![("variant", text(variant)), ("dataset", text(dataset))]
            }
            Refusal::StudyVariantUnaligned {
                variant,
                dataset,
                items,
                baseline,
                baseline_items,
            } => vec![
                ("variant", text(variant)),
                ("dataset", text(dataset)),
                ("items", Detail::Number(*items)),
                ("baseline", text(baseline)),
                ("baseline_items", Detail::Number(*baseline_items)),
            ],
            Refusal::QueuePaused { since } => vec![("since", Detail::Time(since.clone()))],
            Refusal::SlotsEmpty { item, slots } => vec![
                ("item", text(item)),
                ("slots", Detail::Text(slot_list(slots))),
                ("count", Detail::Number(slots.len() as u64)),
            ],
            Refusal::ReasonMissing { item, action } => {
                vec![("item", text(item)), ("action", text(action.as_str()))]
            }
            Refusal::DraftInvalid { item, problem } => {
                let n = |v: usize| Detail::Number(v as u64);
                let mut details = vec![("item", text(item))];
                // A slot as a person counts it, from 1, as `slots_empty` names them.
                details.extend(match problem {
                    DraftProblem::SlotCount {
                        field,
                        given,
                        expected,
                    } => vec![
                        ("field", text(field)),
                        ("given", n(*given)),
                        ("expected", n(*expected)),
                    ],
                    DraftProblem::LabelOutOfRange {
                        field,
                        slot,
                        label,
                        labels,
                    } => vec![
                        ("field", text(field)),
                        ("slot", n(slot + 1)),
                        ("label", n(usize::from(*label))),
                        ("labels", n(*labels)),
                    ],
                    DraftProblem::PlacedTwice { field, slot, label } => vec![
                        ("field", text(field)),
                        ("slot", n(slot + 1)),
                        ("label", n(usize::from(*label))),
                    ],
                    DraftProblem::HistoryTooLong { entries, most } => {
                        vec![("entries", n(*entries)), ("most", n(*most))]
                    }
                });
                details
            }
            Refusal::ReasonTooLong { limit } => vec![("limit", Detail::Number(*limit))],
            Refusal::PasswordTooShort { chars, least } => vec![
                ("chars", Detail::Number(*chars)),
                ("least", Detail::Number(*least)),
            ],
            Refusal::RunPrice { field, price } => {
                vec![("field", text(field)), ("price", text(price))]
            }
            Refusal::FieldsRequired { fields } | Refusal::ExactlyOneOf { fields } => {
                vec![("fields", text(&fields.join(", ")))]
            }
            Refusal::BothOrNeither { fields } => vec![("fields", text(&fields.join(", ")))],
            Refusal::NotWith { field, other } => {
                vec![("field", text(field)), ("other", text(other))]
            }
            Refusal::BadValue {
                field,
                value,
                expected,
            } => {
                let mut details = vec![("field", text(field)), ("value", text(value))];
                match expected {
                    Expected::WholeNumber { least, most }
                    | Expected::NumberBetween { least, most } => {
                        details.push(("least", Detail::Number(*least)));
                        details.push(("most", Detail::Number(*most)));
                    }
                    Expected::WholeNumberFrom { least } => {
                        details.push(("least", Detail::Number(*least)));
                    }
                    Expected::PlainName { most } => details.push(("most", Detail::Number(*most))),
                    Expected::OneOf(words) => details.push(("choices", text(&words.join(", ")))),
                    Expected::Number
                    | Expected::Fraction
                    | Expected::SubmissionId
                    | Expected::ReportedId => {}
                }
                details
            }
        }
    }

    /// One refusal of every variant, for the checks that every code is documented and every
    /// variant has its message in every catalogue.
    pub fn examples() -> Vec<Refusal> {
        let s = |v: &str| v.to_owned();
        vec![
            Refusal::NoDataset { dataset: s("demo") },
            Refusal::NoItem {
                dataset: s("demo"),
                item: s("a1"),
            },
            Refusal::NoAnnotator {
                annotator: s("ann"),
            },
            Refusal::NoEpisode {
                episode: s("kitchen"),
            },
            Refusal::NoSubmission { submission: s("7") },
            Refusal::NoRun { run: s("3") },
            Refusal::NoFrame { frame: s("ab12") },
            Refusal::NoAnswerYet { item: s("a1") },
            Refusal::NoStudy { study: s("camera") },
            Refusal::NoToken {
                token: s("ehub_3f2a"),
            },
            Refusal::NoJob { job: s("12") },
            Refusal::NoReported {
                dataset: s("demo"),
                reported: s("4"),
            },
            Refusal::NoCuratorGraphs {
                episode: s("kitchen"),
                curator: s("ann"),
            },
            Refusal::AnswersHidden { dataset: s("demo") },
            Refusal::InviteLinkUsed,
            Refusal::NoModelSubmission {
                dataset: s("demo"),
                model: s("gpt-x"),
            },
            Refusal::NoPublishedSubmission {
                field: s("a"),
                dataset: s("demo"),
                submission: s("9"),
            },
            Refusal::NoPublishedModel {
                field: s("b"),
                dataset: s("demo"),
                model: s("Gamma"),
                models: s("Alpha, Beta"),
            },
            Refusal::NoPaperFile {
                dataset: s("demo"),
                file: s("table9.tex"),
                files: s("table1.tex, table2.tex"),
            },
            Refusal::NoApiRoute {
                path: s("/api/v1/nope"),
            },
            Refusal::NotLoggedIn,
            Refusal::LoginLinkUsed,
            Refusal::AdminOnly {
                annotator: s("ann"),
            },
            Refusal::StaleForm,
            Refusal::NotAssigned {
                dataset: s("demo"),
                item: s("a1"),
            },
            Refusal::ItemFinished { item: s("a1") },
            Refusal::QueuePaused {
                since: s("2026-11-29T12:00:00Z"),
            },
            Refusal::SlotsEmpty {
                item: s("a1"),
                slots: vec![2, 3],
            },
            Refusal::ReasonMissing {
                item: s("a1"),
                action: SkipAction::Flag,
            },
            Refusal::DraftInvalid {
                item: s("a1"),
                problem: DraftProblem::SlotCount {
                    field: s("slots"),
                    given: 2,
                    expected: 3,
                },
            },
            Refusal::DraftInvalid {
                item: s("a1"),
                problem: DraftProblem::LabelOutOfRange {
                    field: s("history[4]"),
                    slot: 1,
                    label: 7,
                    labels: 3,
                },
            },
            Refusal::DraftInvalid {
                item: s("a1"),
                problem: DraftProblem::PlacedTwice {
                    field: s("slots"),
                    slot: 2,
                    label: 1,
                },
            },
            Refusal::DraftInvalid {
                item: s("a1"),
                problem: DraftProblem::HistoryTooLong {
                    entries: 250,
                    most: 200,
                },
            },
            Refusal::ReasonTooLong { limit: 2000 },
            Refusal::PasswordsDiffer,
            Refusal::PasswordTooShort {
                chars: 3,
                least: 10,
            },
            Refusal::EpisodeHasNoGraphs {
                episode: s("kitchen"),
            },
            Refusal::RunPrice {
                field: s("price_input"),
                price: s("-1"),
            },
            Refusal::ImportFolderUnset,
            Refusal::StudyExists { study: s("camera") },
            Refusal::ChallengeNotSplit { dataset: s("demo") },
            Refusal::ChallengeRevealed {
                dataset: s("demo"),
                at_deadline: true,
                at: s("2026-12-01T00:00:00Z"),
            },
            Refusal::ChallengeAnswersPublic { dataset: s("demo") },
            Refusal::ChallengeTooFewItems {
                dataset: s("demo"),
                items: 1,
            },
            Refusal::ChallengeAlreadySplit {
                dataset: s("demo"),
                at: s("2026-11-29T12:00:00Z"),
                by: s("root"),
                seed: 7,
                public_share: s("0.5"),
            },
            Refusal::SelectionNotPublished {
                submission: s("12"),
                visibility: s("private"),
            },
            Refusal::SelectionLimitReached {
                dataset: s("demo"),
                limit: 2,
                account: s("lab"),
                selected: s("3, 4"),
            },
            Refusal::PrivatePartHidden {
                dataset: s("demo"),
                reveal_at: Some(s("2026-12-01T00:00:00Z")),
            },
            Refusal::StudyBaselineMissing { dataset: s("demo") },
            Refusal::StudyVariantMissing {
                variant: s("Camera/30"),
                dataset: s("demo-fov30"),
            },
            Refusal::StudyVariantUnaligned {
                variant: s("Camera/30"),
                dataset: s("demo-fov30"),
                items: 12,
                baseline: s("demo"),
                baseline_items: 40,
            },
        ]
        .into_iter()
        .chain([
            Refusal::EpisodeExists {
                episode: "kitchen".to_owned(),
            },
            Refusal::EpisodeImporting {
                episode: "kitchen".to_owned(),
                since: "2026-11-29T12:00:00Z".to_owned(),
                by: "root".to_owned(),
                lapses_in: 60,
            },
            Refusal::EpisodeTakenOver {
                episode: "kitchen".to_owned(),
                after: 120,
            },
            Refusal::EpisodeNotResolved {
                episode: "kitchen".to_owned(),
                curators: "ann, bo".to_owned(),
            },
            Refusal::TooFewKeyFrames {
                episode: "kitchen".to_owned(),
                key_frames: 2,
                least: 4,
            },
            Refusal::TooFewCurators {
                episode: "kitchen".to_owned(),
                curators: 1,
            },
            Refusal::NoKeyFrame {
                episode: "kitchen".to_owned(),
                curator: "ann".to_owned(),
                frame: 7,
            },
            Refusal::FrameNameUnusable {
                name: "..".to_owned(),
            },
            Refusal::DailyQuotaUsed {
                limit: 2,
                retry_after: 3600,
            },
            Refusal::TotalQuotaUsed { used: 5, limit: 5 },
            Refusal::IdempotencyKeyReused {
                submission: "7".to_owned(),
            },
            Refusal::EmptyList { field: "checks" },
            Refusal::ListedTwice {
                field: "checks",
                item: "a1".to_owned(),
            },
            Refusal::LeavesNoItems {
                field: "items",
                dataset: "demo".to_owned(),
            },
            Refusal::TooFewForGold {
                dataset: "demo".to_owned(),
                items: 1,
            },
            Refusal::GoldAndAttention {
                field: "checks",
                dataset: "demo".to_owned(),
                items: "a1, a2".to_owned(),
            },
            Refusal::AllChosenPaused,
            Refusal::RecipientPaused {
                annotator: "bo".to_owned(),
            },
            Refusal::HandoverToSelf {
                annotator: "ann".to_owned(),
            },
            Refusal::NoRecipient {
                annotator: "ann".to_owned(),
            },
            Refusal::DatasetExists {
                dataset: "demo".to_owned(),
            },
            Refusal::TokenMissing,
            Refusal::AuthorizationMalformed,
            Refusal::TokenUnknown,
            Refusal::ScopeMissing { scope: "submit" },
            Refusal::NotModelOwner {
                dataset: "demo".to_owned(),
                model: "gpt-x".to_owned(),
            },
            Refusal::FieldsRequired {
                fields: vec!["a", "b"],
            },
            Refusal::ExactlyOneOf {
                fields: vec!["share", "items"],
            },
            Refusal::BothOrNeither { fields: ["a", "b"] },
            Refusal::NotWith {
                field: "seed",
                other: "items",
            },
        ])
        .chain(
            vec![
                Expected::WholeNumber {
                    least: 1,
                    most: 200,
                },
                Expected::WholeNumberFrom { least: 0 },
                Expected::Number,
                Expected::NumberBetween {
                    least: 0,
                    most: 100,
                },
                Expected::Fraction,
                Expected::OneOf(vec!["json", "csv"]),
                Expected::PlainName { most: 100 },
                Expected::SubmissionId,
                Expected::ReportedId,
            ]
            .into_iter()
            .map(|expected| Refusal::bad_value("per_page", "x7", expected)),
        )
        .chain(
            [
                ImportPathProblem::NotRelative,
                ImportPathProblem::Missing,
                ImportPathProblem::LeavesFolder,
                ImportPathProblem::NotARelease,
                ImportPathProblem::ReleaseLeavesFolder,
            ]
            .map(|problem| Refusal::ImportPath {
                path: s("releases/new"),
                problem,
            }),
        )
        .collect()
    }
}

/// "2, 3": slots as a person counts them.
fn slot_list(slots: &[usize]) -> String {
    slots
        .iter()
        .map(usize::to_string)
        .collect::<Vec<_>>()
        .join(", ")
}

/// The English sentence: the API's `error` and what the command line prints.
impl fmt::Display for Refusal {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Refusal::NoDataset { dataset } => write!(f, "no dataset named '{dataset}'"),
            Refusal::NoItem { dataset, item } => {
                write!(f, "no item '{item}' in dataset '{dataset}'")
            }
            Refusal::NoAnnotator { annotator } => write!(f, "no annotator named '{annotator}'"),
            Refusal::NoEpisode { episode } => write!(f, "no episode named '{episode}'"),
            Refusal::NoSubmission { submission } => write!(f, "no submission {submission}"),
            Refusal::NoRun { run } => write!(f, "no model run {run}"),
            Refusal::NoFrame { frame } => write!(f, "no frame with hash '{frame}'"),
            Refusal::NoAnswerYet { item } => write!(f, "item '{item}' has no answer from you yet"),
            Refusal::NoStudy { study } => write!(f, "no study named '{study}'"),
            Refusal::NoToken { token } => write!(f, "no live token with id or prefix {token:?}"),
            Refusal::NoJob { job } => write!(f, "job {job} does not exist"),
            Refusal::NoReported { dataset, reported } => {
                write!(f, "dataset '{dataset}' has no reported result {reported}")
            }
            Refusal::NoCuratorGraphs { episode, curator } => write!(
                f,
                "curator '{curator}' stored no graphs of episode '{episode}'"
            ),
            Refusal::AnswersHidden { dataset } => write!(
                f,
                "the answers of dataset '{dataset}' are hidden, so what would show them is not \
                 shown"
            ),
            Refusal::InviteLinkUsed => write!(
                f,
                "this invite link is unknown or has already been used: ask an admin for a new one"
            ),
            Refusal::NoModelSubmission { dataset, model } => {
                write!(f, "no submission of model '{model}' on dataset '{dataset}'")
            }
            Refusal::NoPublishedSubmission {
                field,
                dataset,
                submission,
            } => write!(
                f,
                "`{field}`: dataset '{dataset}' has no published submission {submission}"
            ),
            Refusal::NoPublishedModel {
                field,
                dataset,
                model,
                models,
            } => {
                write!(
                    f,
                    "`{field}`: dataset '{dataset}' has no published row of model '{model}'"
                )?;
                if models.is_empty() {
                    Ok(())
                } else {
                    write!(f, " (its models: {models})")
                }
            }
            Refusal::NoPaperFile {
                dataset,
                file,
                files,
            } => write!(
                f,
                "the paper folder of dataset '{dataset}' has no file '{file}' (it has {files})"
            ),
            Refusal::NoApiRoute { path } => {
                write!(f, "no API route {path}: the routes are listed at /api/docs")
            }
            Refusal::NotLoggedIn => write!(
                f,
                "not logged in, or the session has expired: log in at /login"
            ),
            Refusal::LoginLinkUsed => write!(
                f,
                "this login link is unknown or has already been used: a link logs in once; ask \
                 an admin for a new one, or log in with a password"
            ),
            Refusal::AdminOnly { annotator } => write!(
                f,
                "the admin pages are for admins; '{annotator}' is an annotator"
            ),
            Refusal::StaleForm => write!(
                f,
                "this request lacks the page's CSRF token, or carries a stale one: reload the \
                 page and try again"
            ),
            Refusal::NotAssigned { dataset, item } => write!(
                f,
                "item '{item}' of dataset '{dataset}' is not assigned to you"
            ),
            Refusal::ItemFinished { item } => write!(
                f,
                "item '{item}' is already finished; its answer can no longer change"
            ),
            Refusal::QueuePaused { since } => write!(
                f,
                "your queue is paused by an admin (since {since}): you cannot open, save, \
                 answer or skip items until it is resumed; your drafts are kept"
            ),
            Refusal::DraftInvalid { item, problem } => {
                write!(f, "draft of item '{item}': {problem}")
            }
            Refusal::SlotsEmpty { item, slots } => {
                let (noun, verb) = if slots.len() == 1 {
                    ("slot", "is")
                } else {
                    ("slots", "are")
                };
                write!(
                    f,
                    "item '{item}': {noun} {} {verb} empty; fill every slot before submitting",
                    slot_list(slots)
                )
            }
            Refusal::ReasonMissing { item, action } => write!(
                f,
                "to {} item '{item}', say why in the reason field",
                action.as_str()
            ),
            Refusal::ReasonTooLong { limit } => {
                write!(f, "the reason is over {limit} characters")
            }
            Refusal::PasswordsDiffer => write!(f, "the two passwords differ"),
            Refusal::PasswordTooShort { chars, least } => write!(
                f,
                "the password has {chars} characters; use at least {least}"
            ),
            Refusal::EpisodeHasNoGraphs { episode } => write!(
                f,
                "episode '{episode}' has no scene graphs yet: a curator must set them before \
                 it can be exported"
            ),
            Refusal::RunPrice { field, price } => write!(
                f,
                "{field} must be a price of 0 or more (US dollars per million tokens), not {price}"
            ),
            Refusal::ImportFolderUnset => write!(
                f,
                "this server imports releases from its own disk only when its operator names an \
                 import folder (ENACT_HUB_IMPORT_DIR); otherwise import on the server itself"
            ),
            Refusal::StudyExists { study } => write!(f, "a study named '{study}' exists already"),
            Refusal::StudyBaselineMissing { dataset } => {
                write!(f, "baseline: no dataset named '{dataset}'")
            }
            Refusal::StudyVariantMissing { variant, dataset } => {
                write!(f, "variant {variant}: no dataset named '{dataset}'")
            }
            Refusal::StudyVariantUnaligned {
                variant,
                dataset,
                items,
                baseline,
                baseline_items,
            } => write!(
                f,
                "variant {variant}: none of dataset '{dataset}''s {items} items aligns with \
                 baseline '{baseline}''s {baseline_items} (by id, or by task, type and key \
                 frames); a variant asks the baseline's questions with other images (made from \
                 the baseline's items)"
            ),
            Refusal::ImportPath { path, problem } => match problem {
                ImportPathProblem::NotRelative => write!(
                    f,
                    "path: {path:?} must be a release's path relative to the server's import \
                     folder"
                ),
                ImportPathProblem::Missing => {
                    write!(f, "path: no {path:?} in the server's import folder")
                }
                ImportPathProblem::LeavesFolder => {
                    write!(f, "path: {path:?} leaves the server's import folder")
                }
                ImportPathProblem::NotARelease => write!(
                    f,
                    "path: {path:?} is neither a release folder (with QA/enact_ordering.jsonl) \
                     nor a .jsonl file"
                ),
                ImportPathProblem::ReleaseLeavesFolder => write!(
                    f,
                    "path: the release of {path:?} (its images' folder) leaves the server's \
                     import folder"
                ),
            },
            Refusal::ChallengeNotSplit { dataset } => write!(
                f,
                "dataset '{dataset}' is not split into a public and a private part: an admin \
                 splits it first (POST /api/v1/admin/datasets/{dataset}/challenge/split)"
            ),
            Refusal::ChallengeRevealed {
                dataset,
                at_deadline,
                at,
            } => {
                let how = if *at_deadline {
                    "at its deadline"
                } else {
                    "by hand"
                };
                write!(
                    f,
                    "the private part of dataset '{dataset}' was revealed {how} at {at}: the \
                     final ranking, its settings and its selections are fixed"
                )
            }
            Refusal::ChallengeAnswersPublic { dataset } => write!(
                f,
                "dataset '{dataset}': its answers are public (`answers`), so every submitter can \
                 score any part of it; only a dataset whose answers are hidden can be split \
                 (hide them first: PUT /api/v1/admin/datasets/{dataset}/answers)"
            ),
            Refusal::ChallengeTooFewItems { dataset, items } => write!(
                f,
                "dataset '{dataset}' has {items} items: a split needs two at least"
            ),
            Refusal::ChallengeAlreadySplit {
                dataset,
                at,
                by,
                seed,
                public_share,
            } => write!(
                f,
                "dataset '{dataset}' was split at {at} by {by} (seed {seed}, public share \
                 {public_share}); a split is final"
            ),
            Refusal::SelectionNotPublished {
                submission,
                visibility,
            } => write!(
                f,
                "submission {submission} is {visibility}: only a published submission can be \
                 selected for the final ranking"
            ),
            Refusal::SelectionLimitReached {
                dataset,
                limit,
                account,
                selected,
            } => write!(
                f,
                "the selection limit of dataset '{dataset}' is {limit} submissions per account \
                 (`selection_limit`): account '{account}' has selected {selected}; take one out \
                 first (DELETE /api/v1/submissions/{{id}}/selection)"
            ),
            Refusal::PrivatePartHidden { dataset, reveal_at } => {
                let when = reveal_at
                    .as_deref()
                    .map(|at| format!(" (it will be at {at})"))
                    .unwrap_or_default();
                write!(
                    f,
                    "part=private: the private part of dataset '{dataset}' is not revealed \
                     yet{when}; until then its figures are for admins"
                )
            }
            Refusal::BadValue {
                field,
                value,
                expected,
            } => write!(f, "{field}: {value:?} is not {expected}"),
            Refusal::EpisodeExists { episode } => {
                write!(f, "an episode named '{episode}' exists already")
            }
            Refusal::EpisodeImporting {
                episode,
                since,
                by,
                lapses_in,
            } => write!(
                f,
                "episode '{episode}' is being imported since {since} (by {by}); if that import \
                 was stopped, its claim on the name lapses in {lapses_in} s and the next import \
                 takes the name over"
            ),
            Refusal::EpisodeTakenOver { episode, after } => write!(
                f,
                "the import of episode '{episode}' wrote nothing for over {after} s and another \
                 import of the name took it over; this one stopped"
            ),
            Refusal::EpisodeNotResolved { episode, curators } => write!(
                f,
                "episode '{episode}' has graphs from several curators ({curators}): choose the \
                 ones to export first"
            ),
            Refusal::TooFewKeyFrames {
                episode,
                key_frames,
                least,
            } => write!(
                f,
                "episode '{episode}' has {key_frames} key frames; an export needs at least \
                 {least} (ENACT's shortest step length, 3, orders 4 key frames)"
            ),
            Refusal::TooFewCurators { episode, curators } => write!(
                f,
                "episode '{episode}' has graphs from {curators} curator(s): a comparison needs two"
            ),
            Refusal::NoKeyFrame {
                episode,
                curator,
                frame,
            } => write!(
                f,
                "curator '{curator}' marked no key frame at frame {frame} of episode '{episode}'"
            ),
            Refusal::FrameNameUnusable { name } => write!(
                f,
                "an uploaded frame has no usable file name ({name:?}): frames are ordered by name"
            ),
            Refusal::DailyQuotaUsed { limit, retry_after } => write!(
                f,
                "this token has used its {limit} submissions for today (UTC); try again in \
                 {retry_after} s"
            ),
            Refusal::TotalQuotaUsed { used, limit } => write!(
                f,
                "this token's total quota is used up: {used} of {limit} submissions made; waiting \
                 will not help, ask an admin for a new token or a larger total quota"
            ),
            Refusal::IdempotencyKeyReused { submission } => write!(
                f,
                "this Idempotency-Key was used for submission {submission} with a different body"
            ),
            Refusal::EmptyList { field } => write!(f, "{field}: give one at least"),
            Refusal::ListedTwice { field, item } => {
                write!(f, "{field}: item '{item}' is listed twice")
            }
            Refusal::LeavesNoItems { field, dataset } => write!(
                f,
                "{field}: the list names every item of dataset '{dataset}'; leave some for the \
                 Human row"
            ),
            Refusal::TooFewForGold { dataset, items } => write!(
                f,
                "dataset '{dataset}' has {items} item(s); gold items need at least two, so some \
                 are left for the Human row"
            ),
            Refusal::GoldAndAttention {
                field,
                dataset,
                items,
            } => {
                let (these, other) = if *field == "checks" {
                    ("gold items", "attention checks")
                } else {
                    ("attention checks", "gold items")
                };
                write!(
                    f,
                    "{field}: {items} of dataset '{dataset}' are {these}; they cannot be {other} \
                     too"
                )
            }
            Refusal::AllChosenPaused => write!(
                f,
                "every annotator chosen for the split has a paused queue: resume one or choose \
                 others"
            ),
            Refusal::RecipientPaused { annotator } => write!(
                f,
                "to: annotator '{annotator}' has a paused queue; resume it or choose someone else"
            ),
            Refusal::HandoverToSelf { annotator } => {
                write!(f, "to: '{annotator}' cannot hand items over to themselves")
            }
            Refusal::NoRecipient { annotator } => write!(
                f,
                "no other active annotator with a running queue to hand '{annotator}''s items \
                 to: create one, resume one, or name the recipients"
            ),
            Refusal::DatasetExists { dataset } => {
                write!(f, "a dataset named '{dataset}' exists already")
            }
            Refusal::TokenMissing => write!(
                f,
                "this endpoint needs an API token: send `Authorization: Bearer TOKEN`"
            ),
            Refusal::AuthorizationMalformed => {
                write!(f, "the Authorization header must read `Bearer TOKEN`")
            }
            Refusal::TokenUnknown => write!(f, "the API token is unknown or has been revoked"),
            Refusal::ScopeMissing { scope } => write!(f, "this token lacks the `{scope}` scope"),
            Refusal::NotModelOwner { dataset, model } => write!(
                f,
                "model '{model}' on dataset '{dataset}' was submitted by another account; only \
                 it or an admin may set its metadata"
            ),
            Refusal::FieldsRequired { fields } => {
                write!(f, "this request needs {}", fields.join(" and "))
            }
            Refusal::ExactlyOneOf { fields } => {
                write!(f, "give exactly one of {}", fields.join(", "))
            }
            Refusal::BothOrNeither { fields: [a, b] } => {
                write!(f, "give both {a} and {b}, or neither")
            }
            Refusal::NotWith { field, other } => {
                write!(f, "{field} cannot be given with {other}")
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_variant_has_an_example_with_its_own_code() {
        let examples = Refusal::examples();
        let mut codes: Vec<&str> = examples.iter().map(Refusal::code).collect();
        codes.sort_unstable();
        codes.dedup();
        assert_eq!(codes.len(), examples.len(), "two variants share a code");
        for code in codes {
            assert!(
                code.bytes().all(|b| b.is_ascii_lowercase() || b == b'_'),
                "{code} is not snake case"
            );
        }
    }

    #[test]
    fn no_english_sentence_names_a_command_line_flag() {
        for r in Refusal::examples() {
            let text = r.to_string();
            assert!(
                !text.split_whitespace().any(|w| w.starts_with("--")),
                "{}: {text}",
                r.code()
            );
        }
    }

    #[test]
    fn details_name_what_the_sentence_names() {
        let r = Refusal::SlotsEmpty {
            item: "a1".into(),
            slots: vec![2],
        };
        assert_eq!(
            r.to_string(),
            "item 'a1': slot 2 is empty; fill every slot before submitting"
        );
        assert_eq!(
            r.details(),
            vec![
                ("item", Detail::Text("a1".into())),
                ("slots", Detail::Text("2".into())),
                ("count", Detail::Number(1)),
            ]
        );
    }
}
