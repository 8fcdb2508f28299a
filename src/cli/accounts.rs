//! People: `token` (API tokens and their accounts) and `annotator` (annotator accounts).

use std::path::Path;
use std::process::ExitCode;

use clap::{Args, Subcommand};

use super::{DbArg, open, operator, refused};
use crate::app::{self, AppError};
use crate::core::credentials::Role;

#[derive(Subcommand)]
pub(super) enum AnnotatorCommand {
    /// Create an annotator and print their single-use invite link (on the last line).
    Create(CreateAnnotatorArgs),
    /// Each annotator's figures on a dataset: gold accuracy with intervals, agreement with the
    /// others, time per item, fast answers, skip and flag rates.
    Quality(super::quality::QualityArgs),
    /// Leave an annotator's answers on a dataset out of its Human row and agreement report
    /// (kept, not deleted; audited).
    Exclude(super::quality::ExclusionArgs),
    /// Count an excluded annotator's answers on a dataset again (audited).
    Include(super::quality::ExclusionArgs),
    /// Pause an annotator's queue: they can read it but not open, save, answer or skip an
    /// item, and no balanced split assigns them items (drafts kept; audited).
    Pause(super::controls::PauseArgs),
    /// Resume a paused queue as it was (audited).
    Resume(super::controls::PauseArgs),
    /// Hand an annotator's unfinished items to other annotators with a balanced split
    /// (finished answers stay; audited).
    Handover(super::controls::HandoverArgs),
}

#[derive(Args)]
pub(super) struct CreateAnnotatorArgs {
    #[command(flatten)]
    db: DbArg,
    /// Login name: letters, digits, '.', '_' and '-'.
    #[arg(long)]
    name: String,
    /// Give the account the admin pages (accounts, assignments, flags, human performance).
    #[arg(long)]
    admin: bool,
    /// Where annotators reach the service; the invite link starts with it.
    #[arg(long, env = "ENACT_HUB_URL", default_value = "http://127.0.0.1:8080")]
    base_url: String,
}

#[derive(Subcommand)]
pub(super) enum TokenCommand {
    /// Create an account's token (the account is created if missing). The token is printed
    /// once, alone on the last line of standard output.
    Create {
        #[command(flatten)]
        db: DbArg,
        /// submitter: submit and read own results; admin: everything.
        #[arg(long, value_enum, default_value = "submitter")]
        role: RoleArg,
        /// The account's name (a person or team).
        #[arg(long)]
        name: String,
        /// Submissions per UTC day (default: the server's --daily-quota).
        #[arg(long)]
        daily_quota: Option<u32>,
        /// Submissions in total (default: the server's --total-quota).
        #[arg(long)]
        total_quota: Option<u32>,
    },
    /// List tokens (never their secrets).
    List {
        #[command(flatten)]
        db: DbArg,
    },
    /// Revoke a token by id or prefix; it stops working at once.
    Revoke {
        #[command(flatten)]
        db: DbArg,
        /// The token's id or prefix, as `token list` shows them.
        token: String,
    },
}

#[derive(Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub(super) enum RoleArg {
    Submitter,
    Admin,
}

impl From<RoleArg> for Role {
    fn from(role: RoleArg) -> Role {
        match role {
            RoleArg::Submitter => Role::Submitter,
            RoleArg::Admin => Role::Admin,
        }
    }
}

pub(super) async fn token(command: TokenCommand) -> anyhow::Result<ExitCode> {
    match command {
        TokenCommand::Create {
            db,
            role,
            name,
            daily_quota,
            total_quota,
        } => {
            let quotas = (daily_quota.map(i64::from), total_quota.map(i64::from));
            create_token(&db.db, &name, role.into(), quotas).await
        }
        TokenCommand::List { db } => list_tokens(&db.db).await,
        TokenCommand::Revoke { db, token } => revoke_token(&db.db, &token).await,
    }
}

/// `token create`: the secret alone on the last line.
async fn create_token(
    db: &Path,
    name: &str,
    role: Role,
    (daily_quota, total_quota): (Option<i64>, Option<i64>),
) -> anyhow::Result<ExitCode> {
    let hub = open(db).await?;
    let created = app::tokens::issue(&hub, &operator(), name, role, daily_quota, total_quota).await;
    hub.close().await;
    let created = match created {
        Ok(c) => c,
        Err(e) => return refused(e),
    };
    println!(
        "created token {} (prefix {}) for {} account '{}'; it is shown only once:",
        created.id, created.prefix, created.role, created.account
    );
    println!("{}", created.token);
    Ok(ExitCode::SUCCESS)
}

/// `token list`: one line per token, never a secret.
async fn list_tokens(db: &Path) -> anyhow::Result<ExitCode> {
    let hub = open(db).await?;
    let tokens = app::tokens::list(&hub).await;
    hub.close().await;
    println!(
        "{:>4}  {:<14} {:<20} {:<9} {:<20} {:<21} status",
        "id", "prefix", "account", "role", "quota (day/total)", "created"
    );
    for t in tokens? {
        let quota = format!(
            "{}/{}",
            t.daily_quota
                .map_or("default".to_owned(), |q| q.to_string()),
            t.total_quota
                .map_or("default".to_owned(), |q| q.to_string())
        );
        let status = t
            .revoked_at
            .map_or_else(|| "live".to_owned(), |at| format!("revoked {at}"));
        println!(
            "{:>4}  {:<14} {:<20} {:<9} {:<20} {:<21} {status}",
            t.id,
            t.prefix,
            t.account,
            t.role.as_str(),
            quota,
            t.created_at
        );
    }
    Ok(ExitCode::SUCCESS)
}

/// `token revoke`: by id or prefix, effective at once.
async fn revoke_token(db: &Path, token: &str) -> anyhow::Result<ExitCode> {
    let hub = open(db).await?;
    let revoked = app::tokens::revoke(&hub, &operator(), token).await;
    hub.close().await;
    match revoked {
        Ok(()) => {
            println!("revoked token {token}");
            Ok(ExitCode::SUCCESS)
        }
        Err(e) => refused(e),
    }
}

/// `annotator …`.
pub(super) async fn annotator(command: AnnotatorCommand) -> anyhow::Result<ExitCode> {
    match command {
        AnnotatorCommand::Create(args) => create_annotator(args).await,
        AnnotatorCommand::Quality(args) => super::quality::quality(args).await,
        AnnotatorCommand::Exclude(args) => super::quality::exclude(args).await,
        AnnotatorCommand::Include(args) => super::quality::include(args).await,
        AnnotatorCommand::Pause(args) => super::controls::pause(args).await,
        AnnotatorCommand::Resume(args) => super::controls::resume(args).await,
        AnnotatorCommand::Handover(args) => super::controls::handover(args).await,
    }
}

async fn create_annotator(args: CreateAnnotatorArgs) -> anyhow::Result<ExitCode> {
    let hub = open(&args.db.db).await?;
    let created = app::annotators::create(&hub, &operator(), &args.name, args.admin).await;
    hub.close().await;
    let invited = match created {
        Ok(invited) => invited,
        Err(AppError::Invalid(problem)) => {
            eprintln!("error: --name: {problem}");
            return Ok(ExitCode::FAILURE);
        }
        Err(AppError::Conflict(problem)) => {
            eprintln!("error: {problem} in {}", args.db.db.display());
            return Ok(ExitCode::FAILURE);
        }
        Err(e) => return refused(e),
    };
    let role = if invited.is_admin {
        "admin"
    } else {
        "annotator"
    };
    println!(
        "created {role} '{}'; send them this single-use link to set a password:",
        invited.name
    );
    println!(
        "{}",
        app::annotators::invite_url(&args.base_url, &invited.invite_token)
    );
    Ok(ExitCode::SUCCESS)
}
