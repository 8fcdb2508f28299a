//! `serve`: the web service, and the admin token it makes sure of at start.

use std::net::SocketAddr;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Duration;

use anyhow::Context;
use clap::Args;

use super::{DEFAULT_DB, MIB, describe_db, frames, resolve};
use crate::app::cache::CacheLimits;
use crate::app::heavy::HeavyLimits;
use crate::app::{self, Hub, Quotas};
use crate::web::{Server, WebConfig, shutdown_signal};

#[derive(Args)]
pub(super) struct ServeArgs {
    /// SQLite database file (created if missing), or a PostgreSQL URL
    /// (postgres://user:password@host/db; also ENACT_HUB_DATABASE_URL). With --demo and no
    /// --db, a temporary SQLite database is used and removed at exit.
    #[arg(long, visible_alias = "database-url", env = "ENACT_HUB_DB")]
    db: Option<PathBuf>,
    /// Address to listen on.
    #[arg(long, env = "ENACT_HUB_ADDR", default_value = "127.0.0.1:8080")]
    addr: SocketAddr,
    #[command(flatten)]
    frames: frames::FramesArg,
    /// Answer requests for frames held in an object store that signs URLs (S3, GCS, Azure)
    /// with a redirect to a URL valid this many seconds, instead of the bytes.
    #[arg(long, value_name = "SECONDS")]
    frame_redirect: Option<u64>,
    /// Reverse proxies (addresses or networks, e.g. 10.0.0.0/8) whose X-Forwarded-For header
    /// names the client, for the login rate limit; repeat or separate with commas. Without
    /// one, every client behind a proxy counts as the proxy.
    #[arg(
        long = "trusted-proxy",
        env = "ENACT_HUB_TRUSTED_PROXIES",
        value_delimiter = ',',
        value_name = "ADDRESS[/BITS]"
    )]
    trusted_proxies: Vec<crate::web::forwarded::TrustedProxy>,
    /// An environment variable a model run started on the server may take its API key from
    /// (repeat, or separate with commas). Read once at start (it must be set); a run names
    /// only the variable, and the server refuses any variable not given here.
    #[arg(
        long = "endpoint-key",
        env = "ENACT_HUB_ENDPOINT_KEYS",
        value_delimiter = ',',
        value_name = "VAR"
    )]
    endpoint_keys: Vec<String>,
    /// The folder admins may import releases from over the API or the admin page (`POST
    /// /api/v1/admin/imports` names a release by its path under it); without it such imports
    /// are refused. Every instance working jobs needs the same folder (a shared volume).
    #[arg(long, env = "ENACT_HUB_IMPORT_DIR", value_name = "DIR")]
    import_dir: Option<PathBuf>,
    /// A bearer token that `GET /metrics` accepts besides admin tokens: give it to the
    /// Prometheus scraper (`authorization: {credentials: ...}`).
    #[arg(
        long,
        env = "ENACT_HUB_METRICS_TOKEN",
        hide_env_values = true,
        value_name = "TOKEN"
    )]
    metrics_token: Option<String>,
    /// Seconds a job's lease (a model run, a rescore) lasts unless renewed: when an instance
    /// dies, another (or this one restarted) takes its jobs over this long after.
    #[arg(long, env = "ENACT_HUB_JOB_LEASE", default_value_t = app::jobs::JobSettings::default().lease.as_secs_f64(), value_name = "SECONDS", value_parser = lease_seconds)]
    job_lease: f64,
    /// The file holding the key statements are signed with (made on first start when
    /// missing, mode 0600). Default: `<db>.signing-key` beside a SQLite database; on
    /// PostgreSQL give every instance the same file, else each signs with a key of its own that
    /// is lost when it stops.
    #[arg(long, env = "ENACT_HUB_SIGNING_KEY", value_name = "FILE")]
    signing_key: Option<PathBuf>,
    /// The hub's public URL, as its signed statements name it (e.g. https://hub.example.org).
    #[arg(long, env = "ENACT_HUB_PUBLIC_URL", value_name = "URL")]
    public_url: Option<String>,
    /// Generate the built-in demo dataset at start and serve it (as dataset "demo").
    #[arg(long)]
    demo: bool,
    /// Largest request body accepted, in bytes.
    #[arg(long, default_value_t = WebConfig::default().body_limit)]
    body_limit: usize,
    /// Seconds a request may take before it is answered with 408.
    #[arg(long, default_value_t = 30)]
    request_timeout: u64,
    /// Memory for caching frame images, in MiB.
    #[arg(long, default_value_t = CacheLimits::default().frame_bytes / MIB)]
    frame_cache_mib: u64,
    /// Memory for caching items (their JSON and decoded form), in MiB.
    #[arg(long, default_value_t = CacheLimits::default().item_bytes / MIB)]
    item_cache_mib: u64,
    /// Annotators' item standings kept in memory, in entries.
    #[arg(long, default_value_t = CacheLimits::default().standing_entries)]
    standing_cache_entries: u64,
    /// Datasets whose scoring targets (every item's signatures) are kept in memory.
    #[arg(long, default_value_t = CacheLimits::default().target_datasets)]
    target_cache_datasets: u64,
    /// Datasets whose leaderboard is kept built in memory.
    #[arg(long, default_value_t = CacheLimits::default().board_datasets)]
    board_cache_datasets: u64,
    /// SQLite's page cache over all connections, in MiB.
    #[arg(long, default_value_t = CacheLimits::default().db_page_cache_bytes / MIB)]
    db_cache_mib: u64,
    /// Largest submission body accepted, in bytes.
    #[arg(long, default_value_t = WebConfig::default().submission_body_limit)]
    submission_body_limit: usize,
    /// Threads for heavy work (scoring submissions, rescoring, error analyses, reports,
    /// imports' validation); the default is one per core.
    #[arg(long, env = "ENACT_HUB_HEAVY_THREADS", default_value_t = HeavyLimits::default().threads, value_name = "N")]
    heavy_threads: usize,
    /// Heavy work waiting for a thread beyond those running; a request that would wait
    /// beyond this is answered 503 with Retry-After.
    #[arg(long, env = "ENACT_HUB_HEAVY_QUEUE", default_value_t = HeavyLimits::default().queue, value_name = "N")]
    heavy_queue: usize,
    /// The heavy-work threads' nice value on Linux, 0 to 19: the higher, the sooner they give
    /// a core up to page loads and answers (0: the server's own priority).
    #[arg(long, env = "ENACT_HUB_HEAVY_NICE", default_value_t = HeavyLimits::default().nice, value_name = "NICE")]
    heavy_nice: i32,
    /// Submissions a token may make per UTC day (rejected ones count too).
    #[arg(long, default_value_t = Quotas::default().daily)]
    daily_quota: i64,
    /// Submissions a token may make in total (rejected ones count too).
    #[arg(long, default_value_t = Quotas::default().total)]
    total_quota: i64,
}

pub(super) async fn serve(args: ServeArgs) -> anyhow::Result<ExitCode> {
    // Held until the server stops: dropping it removes the temporary demo database.
    let mut _temporary = None;
    let db = match (&args.db, args.demo) {
        (Some(db), _) => db.clone(),
        (None, true) => {
            let dir = tempfile::tempdir().context("cannot create a temporary directory")?;
            let db = dir.path().join("demo.db");
            _temporary = Some(dir);
            db
        }
        (None, false) => resolve(Path::new(DEFAULT_DB)),
    };
    let limits = CacheLimits {
        item_bytes: args.item_cache_mib * MIB,
        standing_entries: args.standing_cache_entries,
        target_datasets: args.target_cache_datasets,
        board_datasets: args.board_cache_datasets,
        frame_bytes: args.frame_cache_mib * MIB,
        db_page_cache_bytes: args.db_cache_mib * MIB,
    };
    let heavy = HeavyLimits {
        threads: args.heavy_threads,
        queue: args.heavy_queue,
        nice: args.heavy_nice,
    }
    .checked()
    .map_err(anyhow::Error::msg)?;
    let frame_store = args.frames.store()?;
    let hub = Hub::open_serving(&db, &limits)
        .await?
        .with_heavy_limits(heavy)
        .with_kept(Quotas {
            daily: args.daily_quota,
            total: args.total_quota,
        })
        .with_frame_store(frame_store, args.frame_redirect.map(Duration::from_secs))
        .with_kept(app::runs::EndpointKeys::from_env(
            args.endpoint_keys.clone(),
        )?)
        .with_kept(app::import_jobs::ImportDir(args.import_dir.clone()));
    let hub = app::signing::with_signing(
        hub,
        args.signing_key.clone(),
        args.public_url.clone().filter(|u| !u.trim().is_empty()),
    );
    app::make_caches(&hub);
    prepare_signing_key(&hub).await?;
    if args.demo {
        app::demo::load(&hub).await?;
    }
    ensure_admin_token(&hub).await?;
    // Before the port opens: the first readers find the boards built.
    let warming = std::time::Instant::now();
    let boards = app::leaderboard::warm(&hub).await?;
    tracing::info!(
        boards,
        seconds = warming.elapsed().as_secs_f64(),
        "leaderboards built"
    );
    let config = WebConfig {
        body_limit: args.body_limit,
        request_timeout: Duration::from_secs(args.request_timeout),
        submission_body_limit: args.submission_body_limit,
        trusted_proxies: args.trusted_proxies.clone(),
        metrics_token: args.metrics_token.clone().filter(|t| !t.trim().is_empty()),
    };
    let server = Server::bind(args.addr, hub.clone(), &config)
        .await
        .with_context(|| format!("cannot listen on {}", args.addr))?;
    let addr = server.local_addr()?;
    tracing::info!(
        %addr,
        db = %describe_db(&db),
        frames = hub.frame_store().describe(),
        "enact-hub is listening on http://{addr}/"
    );
    if args.demo {
        let link = app::demo::annotator_link(&hub)
            .await
            .map_err(anyhow::Error::from)?;
        eprintln!("enact-hub is serving the demo on http://{addr}/");
        eprintln!("annotate at once (a single-use login link for the demo admin):");
        println!("http://{addr}/login/link/{link}");
        if args.db.is_none() {
            eprintln!("(the demo database is temporary; give --db FILE to keep it)");
        }
    }
    // Verdicts and items a replacing import killed after its cut-over left.
    let sweeper = hub.clone();
    tokio::spawn(async move {
        match app::import::sweep_replaced_verdicts(&sweeper).await {
            Ok(swept) if swept.verdicts > 0 => tracing::info!(
                verdicts = swept.verdicts,
                submissions = swept.submissions,
                "deleted the verdicts of items replacing imports replaced"
            ),
            Ok(_) => {}
            Err(e) => tracing::warn!(error = %e, "sweeping replaced items' verdicts failed"),
        }
        // Replaced items a swapping cut-over left under its retired row.
        match app::import::delete_retired_datasets(&sweeper).await {
            Ok(deleted) if deleted.items > 0 || deleted.datasets > 0 => tracing::info!(
                items = deleted.items,
                datasets = deleted.datasets,
                "deleted the items replacing imports replaced"
            ),
            Ok(_) => {}
            Err(e) => tracing::warn!(error = %e, "deleting replaced items failed"),
        }
    });
    let worker = app::jobs::Worker::spawn(
        hub.clone(),
        app::job_handlers(),
        app::jobs::JobSettings {
            lease: Duration::from_secs_f64(args.job_lease),
            ..app::jobs::JobSettings::default()
        },
    );
    let served = server.run(shutdown_signal()).await;
    // Jobs in progress let go of their leases, to be resumed at the next start (or at once by
    // another instance).
    worker.stop().await;
    served?;
    hub.close().await;
    Ok(ExitCode::SUCCESS)
}

/// The key statements are signed with, made on the first start (a key file that cannot be
/// read, or holds a retired key, stops the server here).
async fn prepare_signing_key(hub: &Hub) -> anyhow::Result<()> {
    let key = app::signing::prepare(hub).await?;
    match app::signing::source(hub) {
        app::signing::KeySource::File(path) => tracing::info!(
            keyid = %key.keyid,
            file = %path.display(),
            "statements are signed with key {}",
            key.keyid
        ),
        app::signing::KeySource::Process => tracing::warn!(
            keyid = %key.keyid,
            "statements are signed with a key of this process only, lost when it stops: give \
             --signing-key FILE (ENACT_HUB_SIGNING_KEY) to keep one across restarts and instances"
        ),
    }
    Ok(())
}

/// A job lease in seconds: from 1 s (renewals must fit in it) to a day.
fn lease_seconds(text: &str) -> Result<f64, String> {
    let seconds: f64 = text
        .trim()
        .parse()
        .map_err(|_| format!("'{text}' is not a number of seconds"))?;
    if (1.0..=86_400.0).contains(&seconds) {
        Ok(seconds)
    } else {
        Err(format!(
            "a job lease must be 1 to 86400 seconds, not {seconds}"
        ))
    }
}

/// The admin token: ENACT_HUB_ADMIN_TOKEN if set (stored hashed on first sight), otherwise one
/// generated at the first start and printed once on standard output.
async fn ensure_admin_token(hub: &Hub) -> anyhow::Result<()> {
    let operator = std::env::var("ENACT_HUB_ADMIN_TOKEN")
        .ok()
        .filter(|t| !t.is_empty());
    match app::tokens::ensure_admin_token(hub, operator.as_deref()).await? {
        app::tokens::AdminToken::Present => {}
        app::tokens::AdminToken::StoredFromOperator(prefix) => {
            tracing::info!(%prefix, "admin token from ENACT_HUB_ADMIN_TOKEN stored");
        }
        app::tokens::AdminToken::Generated(token) => {
            eprintln!(
                "created the admin API token (shown only this once; set ENACT_HUB_ADMIN_TOKEN to \
                 choose your own):"
            );
            println!("{token}");
        }
    }
    Ok(())
}
