//! Agreement among annotators: the paper's cross-annotation protocol (run once per dataset),
//! Krippendorff's alpha over the overlapping answers, and the dataset's agreement report.

use super::{AppError, Hub, audit, datasets, error_analysis, leaderboard};
use crate::Lane;
use crate::core::agreement::protocol::{ProtocolError, ProtocolPlan, plan_cross_assignments};
use crate::core::agreement::report::export::{ErrorRow, audit_file, bundle_files, error_files};
use crate::core::agreement::report::{
    AgreementReport, AgreementSection, ItemScore, ProtocolStamp, ReportError, ReportInputs,
    SubmissionInput, agreement_section, build_report, dataset_content_hash, overlapping_answers,
};
use crate::core::agreement::{BootstrapConfig, MeasurementLevel, OrderingEncoding};
use crate::core::audit::{Actor, AuditAction};
use crate::core::bundle::BundleFile;
use crate::store;
use crate::store::agreement::AgreementRound;
use crate::store::datasets::Dataset;
use crate::store::db::UniqueKey;

/// Why the protocol did not run on a dataset.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ProtocolRefusal {
    #[error(
        "the agreement protocol already ran on this dataset on {} (k = {}, seed = {}, {} items \
         drawn); it runs once per dataset so that the recorded sample stays the one used",
        .0.created_at, .0.items_per_cell, .0.seed, .0.samples
    )]
    AlreadyRan(AgreementRound),
    #[error(transparent)]
    Plan(#[from] ProtocolError),
}

impl ProtocolRefusal {
    fn into_error(self, dataset: &str) -> AppError {
        let message = format!("dataset '{dataset}': {self}");
        match self {
            ProtocolRefusal::AlreadyRan(_) => AppError::Conflict(message),
            ProtocolRefusal::Plan(_) => AppError::Invalid(message),
        }
    }
}

/// What a protocol run did.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ProtocolRun {
    pub dataset: String,
    pub plan: ProtocolPlan,
    pub annotators: Vec<i64>,
    pub assignments_added: u64,
}

/// Draws `items_per_cell` completed primary items per annotator × direction × step length and
/// assigns each to the other annotators, all in one transaction; `started_by` is the admin who
/// ran it, if any. A second run on the same dataset is refused (409).
pub async fn run_protocol(
    hub: &Hub,
    actor: &Actor,
    dataset: &str,
    items_per_cell: usize,
    seed: u64,
    started_by: Option<i64>,
) -> Result<ProtocolRun, AppError> {
    let dataset = datasets::by_name(hub, dataset).await?;
    let mut tx = hub.write(Lane::Interactive).await?;
    if let Some(existing) = store::agreement::round(&mut tx, dataset.id).await? {
        return Err(ProtocolRefusal::AlreadyRan(existing).into_error(&dataset.name));
    }
    let answers = store::agreement::primary_answers(&mut tx, dataset.id).await?;
    let annotators = store::agreement::primary_annotators(&mut tx, dataset.id).await?;
    let plan = plan_cross_assignments(&answers, &annotators, items_per_cell, seed)
        .map_err(|e| ProtocolRefusal::from(e).into_error(&dataset.name))?;
    let added = match store::agreement::insert_round(&mut tx, dataset.id, &plan, started_by).await {
        Ok(added) => added,
        // The round was read above inside this write transaction, and write transactions are
        // serialised on both databases, so this is a second line of defence: a run that got
        // there first anyway is reported as the run it was. The failed statement ends a
        // PostgreSQL transaction, so the round is read after rolling back.
        Err(e) if UniqueKey::AGREEMENT_ROUND.is_violated_by(&e) => {
            tx.rollback().await?;
            let mut conn = hub.conn().await?;
            let existing = store::agreement::round(&mut conn, dataset.id)
                .await?
                .ok_or_else(|| AppError::internal(e))?;
            return Err(ProtocolRefusal::AlreadyRan(existing).into_error(&dataset.name));
        }
        Err(e) => return Err(e.into()),
    };
    audit::record(
        &mut tx,
        actor,
        AuditAction::ProtocolRun,
        format!("dataset {}", dataset.name),
        Some(&dataset.name),
        format!(
            "{items_per_cell} items per cell, seed {seed}; {added} cross-assignments to {} \
             annotators",
            annotators.len()
        ),
    )
    .await?;
    tx.commit().await?;
    Ok(ProtocolRun {
        dataset: dataset.name,
        plan,
        annotators,
        assignments_added: added,
    })
}

/// The content hash of a stored dataset (over its items' ids and content hashes), and its
/// number of items.
pub(crate) async fn dataset_hash(
    hub: &Hub,
    dataset: &Dataset,
) -> Result<(String, usize), AppError> {
    let mut conn = hub.conn().await?;
    let rows = store::items::content_hashes(&mut conn, dataset.id).await?;
    let hash = dataset_content_hash(rows.iter().map(|(id, hash)| (id.as_str(), hash.as_str())));
    Ok((hash, rows.len()))
}

/// How agreement is computed: the encoding of answers, the level and the bootstrap.
#[derive(Debug, Clone, Copy)]
pub struct AgreementOptions {
    pub encoding: OrderingEncoding,
    pub level: Option<MeasurementLevel>,
    pub bootstrap: BootstrapConfig,
}

/// Alpha over the items two or more annotators answered, with the dataset's content hash.
pub async fn agreement(
    hub: &Hub,
    dataset: &str,
    options: AgreementOptions,
) -> Result<(String, AgreementSection), AppError> {
    let dataset = datasets::by_name(hub, dataset).await?;
    let mut conn = hub.conn().await?;
    let answers = store::agreement::annotator_answers(&mut conn, dataset.id).await?;
    drop(conn);
    let (hash, _) = dataset_hash(hub, &dataset).await?;
    let unavailable =
        |e: &dyn std::fmt::Display| AppError::Invalid(format!("dataset '{}': {e}", dataset.name));
    let overlap = overlapping_answers(&answers).map_err(|e| unavailable(&e))?;
    let section = hub
        .heavy()
        .run(move || {
            agreement_section(
                &overlap,
                options.encoding,
                options.level,
                &options.bootstrap,
            )
        })
        .await?
        .map_err(|e| unavailable(&e))?;
    Ok((hash, section))
}

/// How a report is computed: the admin's or the command line's choices.
#[derive(Debug, Clone, Copy)]
pub struct ReportSettings {
    pub encoding: OrderingEncoding,
    pub level: Option<MeasurementLevel>,
    pub bootstrap: BootstrapConfig,
    /// Two published submissions to compare with each other (a − b).
    pub chosen_pair: Option<(i64, i64)>,
}

/// Everything [`build_report`] needs about a stored dataset.
async fn report_inputs(
    hub: &Hub,
    dataset: &Dataset,
    settings: &ReportSettings,
) -> Result<ReportInputs, AppError> {
    let (dataset_hash, dataset_items) = dataset_hash(hub, dataset).await?;
    let mut conn = hub.conn().await?;
    let answers = store::agreement::annotator_answers(&mut conn, dataset.id).await?;
    let mut submissions = Vec::new();
    for s in store::submissions::published(&mut conn, dataset.id).await? {
        let item_scores = store::submissions::verdicts(&mut conn, s.id)
            .await?
            .into_iter()
            .map(|v| ItemScore {
                item_id: v.id,
                direction: v.direction,
                step_length: v.step_length,
                pairwise_accuracy: v.pairwise_accuracy,
            })
            .collect();
        submissions.push(SubmissionInput {
            row: leaderboard::submission_row(&s),
            item_scores,
        });
    }
    let protocol = store::agreement::round(&mut conn, dataset.id)
        .await?
        .map(|r| ProtocolStamp {
            items_per_cell: r.items_per_cell,
            seed: r.seed,
        });
    Ok(ReportInputs {
        dataset: dataset.name.clone(),
        dataset_hash,
        dataset_items,
        answers,
        submissions,
        chosen_pair: settings.chosen_pair,
        encoding: settings.encoding,
        level: settings.level,
        bootstrap: settings.bootstrap,
        protocol,
    })
}

/// The dataset's agreement report, built off the async workers (the bootstrap is CPU work).
pub async fn report(
    hub: &Hub,
    dataset: &str,
    settings: &ReportSettings,
) -> Result<AgreementReport, AppError> {
    let dataset = datasets::by_name(hub, dataset).await?;
    let inputs = report_inputs(hub, &dataset, settings).await?;
    hub.heavy()
        .run(move || build_report(&inputs))
        .await?
        .map_err(|e| match e {
            // The reader's choices: a submission id or a level that does not apply.
            ReportError::UnknownSubmission(_) | ReportError::Agreement(_) => {
                AppError::Invalid(format!("dataset '{}': {e}", dataset.name))
            }
            // Stored answers the verifier or the test cannot use: our side.
            ReportError::Unscorable { .. } | ReportError::Comparison { .. } => {
                AppError::internal(format!("dataset '{}': {e}", dataset.name))
            }
        })
}

/// The report's files (`core::agreement::report::export`) with the error analysis of every
/// published row and the Human row (`errors.json`, `errors.csv`, examples included: bundles
/// are for admins and the command line), and `audit.csv`: the dataset's audit entries.
pub async fn report_bundle(
    hub: &Hub,
    dataset: &str,
    settings: &ReportSettings,
) -> Result<(AgreementReport, Vec<BundleFile>), AppError> {
    let report = report(hub, dataset, settings).await?;
    let (_, rows) = error_analysis::comparison(hub, dataset, usize::MAX, &[], true).await?;
    let labelled: Vec<ErrorRow<'_>> = rows
        .iter()
        .map(|r| ErrorRow {
            label: match r.submission {
                Some(id) => format!("{} (#{id})", r.label),
                None => r.label.clone(),
            },
            submission: r.submission,
            analysis: &r.analysis.analysis,
        })
        .collect();
    let mut files = bundle_files(&report).map_err(AppError::internal)?;
    files.extend(error_files(&report.stamp, &labelled).map_err(AppError::internal)?);
    let entries = audit::of_dataset(hub, &report.stamp.dataset).await?;
    files.push(audit_file(&report.stamp, &entries));
    Ok((report, files))
}

/// Krippendorff's alpha of a reliability-data file, with its bootstrap interval when asked.
#[derive(Debug, serde::Serialize)]
pub struct FileAgreement {
    pub input: String,
    pub level: String,
    /// `None` when alpha is undefined; `reason` says why.
    pub alpha: Option<f64>,
    pub reason: Option<String>,
    pub coders: usize,
    pub units: usize,
    pub units_used: usize,
    pub pairable_values: usize,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub bootstrap: Option<FileBootstrap>,
}

/// The bootstrap interval of a [`FileAgreement`]: units resampled with replacement.
#[derive(Debug, serde::Serialize)]
pub struct FileBootstrap {
    pub resampled: &'static str,
    pub replicates: usize,
    pub undefined_replicates: usize,
    pub confidence_level: f64,
    pub ci_low: Option<f64>,
    pub ci_high: Option<f64>,
    pub seed: Option<u64>,
    pub rng: Option<String>,
}

/// `enact-hub agreement --input FILE`: alpha of the `{"data": [[...], ...]}` file at `input`
/// (one list per coder) at `level`, each unit its own bootstrap item, with an interval when
/// `bootstrap` is given. Refusals name the file and what is wrong in it.
pub fn of_file(
    input: &std::path::Path,
    level: MeasurementLevel,
    bootstrap: Option<&BootstrapConfig>,
) -> Result<FileAgreement, AppError> {
    use crate::core::agreement::{PreparedAlpha, UnitItems, read_reliability_json};
    let refused = |e: &dyn std::fmt::Display| AppError::Invalid(e.to_string());
    let data = read_reliability_json(input).map_err(|e| refused(&e))?;
    let prepared = PreparedAlpha::with_items(&data, level, &UnitItems::one_per_unit(data.units()))
        .map_err(|e| refused(&e))?;
    let estimate = prepared.estimate();
    let bootstrap = match bootstrap {
        Some(config) if config.replicates > 0 => {
            let b = prepared.bootstrap(config).map_err(|e| refused(&e))?;
            Some(FileBootstrap {
                resampled: "units",
                replicates: b.replicates,
                undefined_replicates: b.undefined_replicates,
                confidence_level: b.confidence_level,
                ci_low: b.ci_low,
                ci_high: b.ci_high,
                seed: b.seed,
                rng: b.rng,
            })
        }
        _ => None,
    };
    Ok(FileAgreement {
        input: input.display().to_string(),
        level: level.to_string(),
        alpha: estimate.alpha,
        reason: estimate.reason.as_ref().map(ToString::to_string),
        coders: estimate.coders,
        units: estimate.units,
        units_used: estimate.units_used,
        pairable_values: estimate.pairable_values,
        bootstrap,
    })
}
