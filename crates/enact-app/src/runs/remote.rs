//! A run against a remote hub (`enact-hub run --hub URL --token T`): the same engine as a
//! run in the hub's own database, with the items and frames read over the hub's API and
//! every reply kept in a local cache file instead of a table. The answers are posted to the
//! hub's submission API at the end, under the caller's token.
//!
//! The cache file is JSON lines: a header naming the run (hub, dataset, endpoint, model,
//! parameters, prompt), then one line per reply, appended and fsynced before the item counts
//! as done. Running the same command again reads it and asks only what it does not hold; a
//! line cut short by a crash is dropped (its item was never counted). A failed item asked
//! again gets a second line: the last line of an item says how it ended, and its tokens and
//! attempts are summed over its lines, as the database does.

use std::collections::HashMap;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};
use std::time::SystemTime;

use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};

use enact_outbound::hub::HubClient;

use super::{
    AppError, Asked, CallSettings, ItemOutcome, Ledger, Named, Pending, ProgressFn, RemoteHub,
    RunFailure, RunHead, RunItemRow, RunReport, RunSpec, Stamped, StopFn, Tail, ask_and_report,
    asker, check_settings, named, pending, tally,
};
use crate::core::model_run::{PROMPT_VERSION, prompt_template_hash};

/// The cache file's first line: which run its replies belong to.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
struct CacheHeader {
    enact_hub_run_cache: u32,
    hub: String,
    dataset: String,
    /// The run's name, endpoint, model, parameters and prompt, beside the fields above.
    #[serde(flatten)]
    head: RunHead,
}

/// The cache format's version, in its header.
const CACHE_VERSION: u32 = 1;

/// One reply as the cache file keeps it.
#[derive(Debug, Clone, Serialize, Deserialize)]
struct CacheLine {
    item: String,
    answered: bool,
    /// Why an item that was not answered failed ([`RunFailure::code`]); absent from the lines
    /// of a hub older than failure kinds, which read as `unrecorded`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    failure: Option<String>,
    response: Option<String>,
    finish_reason: Option<String>,
    prompt_tokens: i64,
    completion_tokens: i64,
    latency_ms: i64,
    attempts: i64,
    error: Option<String>,
    done_at: String,
}

impl CacheLine {
    fn of(row: &RunItemRow) -> CacheLine {
        CacheLine {
            item: row.item_id.clone(),
            answered: row.outcome.is_answered(),
            failure: row.outcome.failure().map(RunFailure::code),
            response: row.response.clone(),
            finish_reason: row.finish_reason.clone(),
            prompt_tokens: row.prompt_tokens,
            completion_tokens: row.completion_tokens,
            latency_ms: row.latency_ms,
            attempts: row.attempts,
            error: row.error.clone(),
            done_at: httpdate::fmt_http_date(SystemTime::now()),
        }
    }

    /// The row this line keeps; an error when its failure is no failure's code.
    fn into_row(self) -> Result<RunItemRow, String> {
        let outcome = match (self.answered, self.failure.as_deref()) {
            (true, _) => ItemOutcome::Answered,
            (false, None) => ItemOutcome::Failed(RunFailure::Unrecorded),
            (false, Some(code)) => ItemOutcome::Failed(
                RunFailure::from_code(code)
                    .ok_or_else(|| format!("failure {code:?} is not a failure's code"))?,
            ),
        };
        Ok(RunItemRow {
            item_id: self.item,
            outcome,
            response: self.response,
            finish_reason: self.finish_reason,
            prompt_tokens: self.prompt_tokens,
            completion_tokens: self.completion_tokens,
            latency_ms: self.latency_ms,
            attempts: self.attempts,
            error: self.error,
            done_at: self.done_at,
        })
    }
}

/// The file name a run's cache gets by default: its name, with what a file name cannot
/// hold replaced.
pub fn default_cache(run: &str) -> PathBuf {
    let safe: String = run
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || matches!(c, '.' | '-' | '_' | '@') {
                c
            } else {
                '_'
            }
        })
        .collect();
    PathBuf::from(format!("{safe}.enact-run.jsonl"))
}

/// A cache file's header and each item's reply.
type Cached = (CacheHeader, HashMap<String, RunItemRow>);

/// Reads a cache file: its header and each item's reply (the last line of an item, its
/// tokens and attempts summed). A last line without its newline was cut by a crash: it is
/// cut off the file. Any other unreadable line is an error naming it.
fn read_cache(path: &Path) -> Result<Option<Cached>, AppError> {
    let shown = path.display();
    let bytes = match std::fs::read(path) {
        Ok(b) => b,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(e) => {
            return Err(AppError::Invalid(format!(
                "cannot read the cache {shown}: {e}"
            )));
        }
    };
    let complete = bytes
        .iter()
        .rposition(|&b| b == b'\n')
        .map_or(0, |at| at + 1);
    if complete < bytes.len() {
        let file = std::fs::OpenOptions::new()
            .write(true)
            .open(path)
            .and_then(|f| f.set_len(complete as u64).and_then(|()| f.sync_data()));
        file.map_err(|e| {
            AppError::Invalid(format!(
                "cannot cut the unfinished last line of {shown}: {e}"
            ))
        })?;
        tracing::warn!(cache = %shown, "dropped a reply cut short by a crash");
    }
    let text = std::str::from_utf8(&bytes[..complete])
        .map_err(|e| AppError::Invalid(format!("the cache {shown} is not UTF-8: {e}")))?;
    let mut lines = text.lines().enumerate();
    let Some((_, first)) = lines.next() else {
        return Ok(None);
    };
    let header: CacheHeader = serde_json::from_str(first).map_err(|e| {
        AppError::Invalid(format!(
            "{shown} line 1: not an enact-hub run cache header: {e}"
        ))
    })?;
    if header.enact_hub_run_cache != CACHE_VERSION {
        return Err(AppError::Invalid(format!(
            "{shown} line 1: cache format {} is not {CACHE_VERSION}",
            header.enact_hub_run_cache
        )));
    }
    let mut rows: HashMap<String, RunItemRow> = HashMap::new();
    for (at, line) in lines {
        let line: CacheLine = serde_json::from_str(line)
            .map_err(|e| AppError::Invalid(format!("{shown} line {}: {e}", at + 1)))?;
        let mut row = line
            .into_row()
            .map_err(|e| AppError::Invalid(format!("{shown} line {}: {e}", at + 1)))?;
        if let Some(before) = rows.get(&row.item_id) {
            row.prompt_tokens += before.prompt_tokens;
            row.completion_tokens += before.completion_tokens;
            row.attempts += before.attempts;
        }
        rows.insert(row.item_id.clone(), row);
    }
    Ok(Some((header, rows)))
}

/// Appends `line` to `file` and waits until it is on disk.
fn append_line(file: &Mutex<std::fs::File>, line: &[u8]) -> std::io::Result<()> {
    let mut file = file
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    file.write_all(line)?;
    file.sync_data()
}

/// A remote run's ledger: items and frames over the API, replies in the cache file.
struct RemoteLedger {
    hub: Arc<HubClient>,
    header: CacheHeader,
    /// The run's items, in order.
    ids: Vec<String>,
    cache: Arc<Mutex<std::fs::File>>,
    cache_path: PathBuf,
}

impl Ledger for RemoteLedger {
    async fn item(&self, item: &Pending) -> Result<Asked, AppError> {
        self.hub.item(&self.header.dataset, &item.item_id).await
    }

    async fn record(&self, _item: &Pending, row: &RunItemRow) -> Result<(), AppError> {
        let mut line = serde_json::to_vec(&CacheLine::of(row))?;
        line.push(b'\n');
        let file = self.cache.clone();
        tokio::task::spawn_blocking(move || append_line(&file, &line))
            .await?
            .map_err(|e| {
                AppError::internal(format!(
                    "writing the cache {}: {e}",
                    self.cache_path.display()
                ))
            })
    }

    async fn rows(&self) -> Result<Vec<RunItemRow>, AppError> {
        Ok(match read_cache(&self.cache_path)? {
            Some((_, mut rows)) => self.ids.iter().filter_map(|id| rows.remove(id)).collect(),
            None => Vec::new(),
        })
    }

    fn head(&self) -> &RunHead {
        &self.header.head
    }

    /// A hash of the hub and the run's name: a remote run has no row id here.
    fn run_key(&self) -> String {
        let run = format!("{}\n{}", self.header.hub, self.header.head.run);
        hex::encode(Sha256::digest(run))[..16].to_owned()
    }

    async fn send(&self, stamped: Stamped, key: &str, body: String) -> Result<i64, AppError> {
        let dataset = &self.header.dataset;
        self.hub.submit(dataset, &stamped.metadata, key, body).await
    }
}

/// The datasets of `study` on the remote hub, baseline first.
pub async fn study_datasets(
    hub: &RemoteHub,
    settings: &CallSettings,
    study: &str,
) -> Result<Vec<String>, AppError> {
    HubClient::new(hub, settings)?.study_datasets(study).await
}

/// Runs `spec` against the remote hub: asks every item its cache file does not hold, keeps
/// each reply there as it arrives, then (when every item is done and `spec.submit_as` is
/// set) posts the answers. `cache` defaults to the run's name in the working directory.
pub async fn execute_remote(
    hub: &RemoteHub,
    spec: &RunSpec,
    settings: &CallSettings,
    cache: Option<&Path>,
    progress: ProgressFn<'_>,
    stop: StopFn<'_>,
) -> Result<RunReport, AppError> {
    check_settings(spec, settings)?;
    let client = Arc::new(HubClient::new(hub, settings)?);
    let Named {
        endpoint,
        params,
        name,
    } = named(&spec.dataset, spec)?;
    let header = CacheHeader {
        enact_hub_run_cache: CACHE_VERSION,
        hub: client.base().to_owned(),
        dataset: spec.dataset.clone(),
        head: RunHead {
            run: name.clone(),
            endpoint,
            model: spec.model.clone(),
            params,
            prompt_version: PROMPT_VERSION.to_owned(),
            prompt_hash: prompt_template_hash(),
        },
    };
    let cache_path = cache.map_or_else(|| default_cache(&name), Path::to_path_buf);
    let ids = client.item_ids(&spec.dataset).await?;
    let ids = &ids[..spec.limit.map_or(ids.len(), |l| l.min(ids.len()))];
    let stored = match read_cache(&cache_path)? {
        Some((found, rows)) => {
            if found != header {
                return Err(AppError::Conflict(format!(
                    "the cache {} holds run '{}' of '{}' with {} on {} ({}), not this run: give \
                     another --cache (or --run) to start a new run",
                    cache_path.display(),
                    found.head.run,
                    found.dataset,
                    found.head.model,
                    found.head.endpoint,
                    found.hub
                )));
            }
            rows
        }
        None => HashMap::new(),
    };
    let file = std::fs::OpenOptions::new()
        .create(true)
        .append(true)
        .open(&cache_path)
        .map_err(|e| {
            AppError::Invalid(format!(
                "cannot open the cache {}: {e}",
                cache_path.display()
            ))
        })?;
    let file = Arc::new(Mutex::new(file));
    if file
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner)
        .metadata()
        .map(|m| m.len() == 0)
        .unwrap_or(false)
    {
        let mut line = serde_json::to_vec(&header)?;
        line.push(b'\n');
        append_line(&file, &line).map_err(|e| {
            AppError::Invalid(format!(
                "cannot write the cache {}: {e}",
                cache_path.display()
            ))
        })?;
    }

    let mut state = tally(
        ids.iter().filter_map(|id| stored.get(id.as_str())),
        spec.prices,
    );
    state.total = ids.len();
    progress(&state);
    let todo = pending(
        ids.iter().enumerate().map(|(at, id)| {
            let answered = stored.get(id.as_str()).map(|row| row.outcome.is_answered());
            (at as i64, id.as_str(), answered)
        }),
        spec.retry_failed,
    );
    drop(stored);
    let asker = Arc::new(
        asker::Asker::new(&header.head.endpoint, settings.clone()).map_err(AppError::internal)?,
    );
    let tail = Tail {
        dataset: spec.dataset.clone(),
        model: &spec.model,
        run: name,
        run_id: None,
        params: &spec.params,
        spec,
        settings,
    };
    let ledger = Arc::new(RemoteLedger {
        hub: client,
        header,
        ids: ids.to_vec(),
        cache: file,
        cache_path,
    });
    ask_and_report(ledger, asker, tail, todo, state, progress, stop).await
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(item: &str, answered: bool, tokens: i64) -> RunItemRow {
        RunItemRow {
            item_id: item.to_owned(),
            outcome: if answered {
                ItemOutcome::Answered
            } else {
                ItemOutcome::Failed(RunFailure::Status(500))
            },
            response: answered.then(|| "[1, 2]".to_owned()),
            finish_reason: Some("stop".to_owned()),
            prompt_tokens: tokens,
            completion_tokens: 1,
            latency_ms: 5,
            attempts: 1,
            error: (!answered).then(|| "HTTP 500: down".to_owned()),
            done_at: String::new(),
        }
    }

    fn header() -> CacheHeader {
        CacheHeader {
            enact_hub_run_cache: CACHE_VERSION,
            hub: "http://hub".into(),
            dataset: "d".into(),
            head: RunHead {
                run: "r".into(),
                endpoint: "http://m/v1".into(),
                model: "m".into(),
                params: "{}".into(),
                prompt_version: PROMPT_VERSION.into(),
                prompt_hash: prompt_template_hash(),
            },
        }
    }

    fn line<T: Serialize>(value: &T) -> Vec<u8> {
        let mut line = serde_json::to_vec(value).unwrap();
        line.push(b'\n');
        line
    }

    /// The header stays one flat JSON object, as caches written before the run's head was a
    /// struct of its own hold it.
    #[test]
    fn a_cache_header_is_one_flat_object_as_before() {
        let flat = serde_json::json!({
            "enact_hub_run_cache": CACHE_VERSION,
            "run": "r",
            "hub": "http://hub",
            "dataset": "d",
            "endpoint": "http://m/v1",
            "model": "m",
            "params": "{}",
            "prompt_version": PROMPT_VERSION,
            "prompt_hash": prompt_template_hash(),
        });
        let read: CacheHeader = serde_json::from_value(flat.clone()).unwrap();
        assert_eq!(read, header());
        assert_eq!(serde_json::to_value(header()).unwrap(), flat);
    }

    #[test]
    fn a_cache_keeps_the_last_reply_of_an_item_and_sums_its_tokens() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("c.jsonl");
        let mut bytes = line(&header());
        bytes.extend(line(&CacheLine::of(&row("a", false, 10))));
        bytes.extend(line(&CacheLine::of(&row("b", true, 7))));
        bytes.extend(line(&CacheLine::of(&row("a", true, 20))));
        std::fs::write(&path, &bytes).unwrap();
        let (found, rows) = read_cache(&path).unwrap().unwrap();
        assert_eq!(found, header());
        assert_eq!(rows.len(), 2);
        let a = &rows["a"];
        assert_eq!(a.outcome, ItemOutcome::Answered);
        assert_eq!(
            (a.prompt_tokens, a.completion_tokens, a.attempts),
            (30, 2, 2)
        );
        assert_eq!(rows["b"].prompt_tokens, 7);
    }

    #[test]
    fn a_failure_s_kind_is_kept_in_the_cache_and_an_older_line_reads_as_unrecorded() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("c.jsonl");
        let mut bytes = line(&header());
        bytes.extend(line(&CacheLine::of(&row("a", false, 1))));
        // A line as a hub before failure kinds wrote it: no `failure`.
        let mut older = serde_json::to_value(CacheLine::of(&row("b", false, 1))).unwrap();
        older.as_object_mut().unwrap().remove("failure");
        bytes.extend(line(&older));
        std::fs::write(&path, &bytes).unwrap();
        let (_, rows) = read_cache(&path).unwrap().unwrap();
        assert_eq!(
            rows["a"].outcome,
            ItemOutcome::Failed(RunFailure::Status(500))
        );
        assert_eq!(
            rows["b"].outcome,
            ItemOutcome::Failed(RunFailure::Unrecorded)
        );

        let mut unknown = serde_json::to_value(CacheLine::of(&row("c", false, 1))).unwrap();
        unknown["failure"] = "gremlins".into();
        bytes.extend(line(&unknown));
        std::fs::write(&path, &bytes).unwrap();
        let e = read_cache(&path).unwrap_err().to_string();
        assert!(e.contains("line 4") && e.contains("gremlins"), "{e}");
    }

    #[test]
    fn a_line_cut_by_a_crash_is_dropped_and_cut_off_the_file() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("c.jsonl");
        let mut bytes = line(&header());
        bytes.extend(line(&CacheLine::of(&row("a", true, 1))));
        let whole = bytes.len();
        bytes.extend(&line(&CacheLine::of(&row("b", true, 1)))[..20]);
        std::fs::write(&path, &bytes).unwrap();
        let (_, rows) = read_cache(&path).unwrap().unwrap();
        assert_eq!(rows.keys().collect::<Vec<_>>(), ["a"]);
        assert_eq!(std::fs::metadata(&path).unwrap().len() as usize, whole);
    }

    #[test]
    fn a_bad_line_in_the_middle_is_an_error_naming_it() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("c.jsonl");
        let mut bytes = line(&header());
        bytes.extend(b"{not json}\n");
        bytes.extend(line(&CacheLine::of(&row("a", true, 1))));
        std::fs::write(&path, &bytes).unwrap();
        let e = read_cache(&path).unwrap_err().to_string();
        assert!(e.contains("line 2"), "{e}");
        std::fs::write(&path, b"{\"x\": 1}\n").unwrap();
        let e = read_cache(&path).unwrap_err().to_string();
        assert!(e.contains("line 1") && e.contains("header"), "{e}");
    }

    #[test]
    fn default_cache_names_are_file_names() {
        assert_eq!(
            default_cache("Qwen/Qwen2.5-VL@enact-0123"),
            PathBuf::from("Qwen_Qwen2.5-VL@enact-0123.enact-run.jsonl")
        );
    }
}
