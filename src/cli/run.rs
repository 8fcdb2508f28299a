//! `enact-hub run`: ask an OpenAI-compatible model every item of a dataset (or of every
//! dataset of a study), keeping each reply in the database as it arrives, and submit the
//! answers. The engine is [`crate::app::runs`]; this file parses, draws the progress bar and
//! prints the summary.

use std::io::IsTerminal;
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Duration;

use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};

use super::{DEFAULT_DB, open, operator, refused};
use crate::app::refusal::Refusal;
use crate::app::runs::{
    self, ApiKey, CallSettings, GenerationParams, Prices, RemoteHub, RunProgress, RunReport,
    RunSpec,
};
use crate::app::{self, AppError};

#[derive(Args)]
pub struct RunArgs {
    /// The dataset to answer (or --study).
    #[arg(required_unless_present = "study", conflicts_with = "study")]
    dataset: Option<String>,
    /// Answer the baseline and every variant dataset of this study, one run each.
    #[arg(long)]
    study: Option<String>,
    /// SQLite database file, or a PostgreSQL URL (postgres://user:password@host/db). Not
    /// used with --hub.
    #[arg(long, visible_alias = "database-url", env = "ENACT_HUB_DB", default_value = DEFAULT_DB)]
    db: PathBuf,
    /// Run against a hub over its API instead of a database: items and frames are read from
    /// it, replies kept in --cache, the answers submitted to it with --token.
    #[arg(long, value_name = "URL", requires = "token")]
    hub: Option<String>,
    /// A token of the hub's with the submit scope (with --hub).
    #[arg(long, env = "ENACT_HUB_TOKEN", hide_env_values = true)]
    token: Option<String>,
    /// The file that keeps a --hub run's replies (default: the run's name with
    /// `.enact-run.jsonl`, in the working directory). Run again with the same file to go on.
    #[arg(long, value_name = "FILE", requires = "hub")]
    cache: Option<PathBuf>,
    /// The chat-completions server's base URL, e.g. http://127.0.0.1:8000/v1 (vLLM) or
    /// https://api.openai.com/v1; `/chat/completions` is appended. No key in it.
    #[arg(long)]
    endpoint: String,
    /// The model name sent to the endpoint.
    #[arg(long)]
    model: String,
    /// The environment variable holding the endpoint's API key (its value is sent as a
    /// bearer token and never stored or printed).
    #[arg(long, value_name = "VAR")]
    api_key_env: Option<String>,
    /// The run's name (default: made from the dataset, endpoint, model and parameters, so the
    /// same command resumes the same run).
    #[arg(long = "run", value_name = "NAME")]
    run: Option<String>,
    /// Requests in flight at most; fewer while the endpoint answers 429.
    #[arg(long, default_value_t = 8)]
    concurrency: usize,
    /// Retries of a request after 5xx, 408, 409, timeouts and connection errors.
    #[arg(long, default_value_t = 5)]
    max_retries: u32,
    /// Seconds per request, reading the reply included.
    #[arg(long, default_value_t = 120.0)]
    timeout: f64,
    /// Seconds before the first retry (doubled per retry, with jitter).
    #[arg(long, default_value_t = 1.0)]
    retry_delay: f64,
    #[arg(long)]
    temperature: Option<f64>,
    #[arg(long)]
    max_tokens: Option<u32>,
    /// Answer only the first N items (the rest are submitted unanswered).
    #[arg(long)]
    limit: Option<usize>,
    /// Ask the items that failed in an earlier run of the same run again.
    #[arg(long)]
    retry_failed: bool,
    /// The model's name on the leaderboard (default: --model).
    #[arg(long, conflicts_with = "no_submit")]
    submit_as: Option<String>,
    /// Keep the replies but do not submit.
    #[arg(long)]
    no_submit: bool,
    /// US dollars per million input tokens, for the cost.
    #[arg(long, default_value_t = 0.0)]
    price_input: f64,
    /// US dollars per million output tokens, for the cost.
    #[arg(long, default_value_t = 0.0)]
    price_output: f64,
    /// Print the summary as JSON.
    #[arg(long)]
    json: bool,
}

fn seconds(flag: &str, value: f64) -> anyhow::Result<Duration> {
    Duration::try_from_secs_f64(value)
        .ok()
        .filter(|d| !d.is_zero() || flag == "--retry-delay")
        .ok_or_else(|| anyhow::anyhow!("{flag} must be a positive number of seconds"))
}

pub async fn run(args: RunArgs) -> anyhow::Result<ExitCode> {
    let api_key = match &args.api_key_env {
        Some(var) => match std::env::var(var) {
            Ok(value) => ApiKey::new(value),
            Err(_) => anyhow::bail!("--api-key-env {var}: the variable is not set"),
        },
        None => None,
    };
    let settings = CallSettings {
        concurrency: args.concurrency,
        max_retries: args.max_retries,
        timeout: seconds("--timeout", args.timeout)?,
        backoff_base: seconds("--retry-delay", args.retry_delay)?,
        api_key,
    };
    let place = match (&args.hub, &args.token) {
        (Some(url), Some(token)) => Place::Remote(RemoteHub {
            url: url.clone(),
            token: token.clone(),
        }),
        (Some(_), None) => anyhow::bail!("--hub needs --token (or ENACT_HUB_TOKEN)"),
        (None, _) => Place::Local(open(&args.db).await?.with_cache_limits(&runs::CACHE_LIMITS)),
    };
    let datasets = match (&args.dataset, &args.study, &place) {
        (Some(d), _, _) => vec![d.clone()],
        (None, Some(study), Place::Local(hub)) => match app::studies::get(hub, study).await {
            Ok(view) => std::iter::once(view.baseline)
                .chain(view.variants.into_iter().map(|v| v.spec.dataset))
                .collect(),
            Err(e) => return refused(e),
        },
        (None, Some(study), Place::Remote(remote)) => {
            match runs::study_datasets(remote, &settings, study).await {
                Ok(datasets) => datasets,
                Err(e) => return refused(e),
            }
        }
        (None, None, _) => anyhow::bail!("give a dataset or --study"),
    };
    if several_caches(&args, datasets.len()) {
        anyhow::bail!(
            "--cache names one file: a --study run keeps one cache per dataset by default"
        );
    }
    let several = datasets.len() > 1;
    let mut reports = Vec::new();
    for dataset in datasets {
        let spec = RunSpec {
            name: args.run.as_ref().map(|n| {
                if several {
                    format!("{n}-{dataset}")
                } else {
                    n.clone()
                }
            }),
            dataset,
            endpoint: args.endpoint.clone(),
            model: args.model.clone(),
            params: GenerationParams {
                temperature: args.temperature,
                max_tokens: args.max_tokens,
            },
            limit: args.limit,
            retry_failed: args.retry_failed,
            submit_as: (!args.no_submit)
                .then(|| args.submit_as.clone().unwrap_or_else(|| args.model.clone())),
            prices: Prices {
                input_usd_per_mtok: args.price_input,
                output_usd_per_mtok: args.price_output,
            },
        };
        let bar = progress_bar(&spec.dataset);
        let draw = |p: &RunProgress| {
            if let Some(bar) = &bar {
                bar.set_length(p.total as u64);
                bar.set_position(p.done as u64);
                bar.set_message(format!(
                    "{} failed, {} in flight, {} tokens, ${:.4}",
                    p.failed,
                    p.in_flight,
                    p.usage.prompt_tokens + p.usage.completion_tokens,
                    p.cost_usd
                ));
            }
        };
        let result = match &place {
            Place::Local(hub) => {
                runs::execute(hub, &operator(), &spec, &settings, &draw, &|| false).await
            }
            Place::Remote(remote) => {
                let cache = args.cache.as_deref();
                runs::execute_remote(remote, &spec, &settings, cache, &draw, &|| false).await
            }
        };
        if let Some(bar) = &bar {
            bar.finish_and_clear();
        }
        match result {
            Ok(report) => {
                if !args.json {
                    print_report(&report);
                    if let Place::Remote(_) = &place {
                        let cache = args
                            .cache
                            .clone()
                            .unwrap_or_else(|| runs::default_cache(&report.run));
                        eprintln!("replies kept in {}", cache.display());
                    }
                }
                reports.push(report);
            }
            Err(AppError::Internal(e)) => return Err(e),
            // The run's own check (`RunSpec::check`) names the API's field; here, the flag.
            Err(AppError::Refused(Refusal::RunPrice { field, price })) => {
                let flag = field.replace('_', "-");
                eprintln!("error: --{flag} must be a price of 0 or more, not {price}");
                return Ok(ExitCode::FAILURE);
            }
            Err(e) => {
                eprintln!("error: {e}");
                return Ok(ExitCode::FAILURE);
            }
        }
    }
    if args.json {
        let out = if several {
            serde_json::to_string_pretty(&reports)?
        } else {
            serde_json::to_string_pretty(&reports[0])?
        };
        println!("{out}");
    }
    Ok(ExitCode::SUCCESS)
}

/// Where a run's items are and its replies go.
enum Place {
    Local(app::Hub),
    Remote(RemoteHub),
}

/// Whether one --cache file was named for several runs.
fn several_caches(args: &RunArgs, runs: usize) -> bool {
    args.cache.is_some() && runs > 1
}

fn progress_bar(dataset: &str) -> Option<ProgressBar> {
    if !std::io::stderr().is_terminal() {
        return None;
    }
    let bar = ProgressBar::new(0);
    bar.set_style(
        ProgressStyle::with_template(&format!(
            "{dataset} {{bar:30}} {{pos}}/{{len}} ({{per_sec}}, {{eta}} left) {{msg}}"
        ))
        .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    bar.enable_steady_tick(Duration::from_millis(250));
    Some(bar)
}

fn print_report(report: &RunReport) {
    let p = &report.progress;
    eprintln!(
        "run '{}' on '{}': {} of {} items answered, {} failed ({} asked now, {} requests, {} \
         refused with 429); {} prompt + {} completion tokens, ${:.4}",
        report.run,
        report.dataset,
        p.answered,
        p.total,
        p.failed,
        p.asked_now,
        p.requests,
        p.refused,
        p.usage.prompt_tokens,
        p.usage.completion_tokens,
        p.cost_usd
    );
    for (reason, n) in &report.failures {
        eprintln!("  failed ×{n}: {reason}");
    }
    match (report.stopped, report.submission) {
        (true, _) => eprintln!("stopped before every item was done: run it again to go on"),
        (false, Some(id)) => eprintln!("submission {id}"),
        (false, None) => eprintln!("not submitted (--no-submit)"),
    }
}
