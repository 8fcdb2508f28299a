//! The hub's statement-signing key: where its secret lives, making it on first need, rotating
//! it, and listing every public key it ever had so that old statements stay verifiable.
//!
//! The secret (an Ed25519 seed) is kept in a key file and never in the database, so nothing
//! made from the database — `enact-hub backup`, a copy of the SQLite file, `migrate-db` — holds
//! it. The file is:
//!
//! - `--signing-key FILE` (`serve`, `keys rotate`) or `ENACT_HUB_SIGNING_KEY` (every command)
//!   when given; on PostgreSQL give every instance and command the same file;
//! - otherwise, for a SQLite database, `<database>.signing-key` beside it, which every process
//!   on that database finds by itself;
//! - otherwise (PostgreSQL without one) there is none: each process makes a key of its own when
//!   it first signs and loses it at exit (its public key stays listed; `serve` warns).
//!
//! A missing file is made (mode 0600) on first need: at a server's start, or by the first
//! command that signs. Every public key is listed in the `signing_keys` table, its id being
//! the first 16 hex digits of the SHA-256 of its raw bytes. A rotation writes a new secret over
//! the file and retires every other key: a retired key signs nothing new, and a process whose
//! key was retired elsewhere (a server, when `enact-hub keys rotate` ran beside it) reads the
//! file again before its next statement.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

use base64::Engine as _;
use base64::engine::general_purpose::STANDARD;

use super::{AppError, Hub, audit};
use crate::Lane;
use crate::core::audit::{Actor, AuditAction};
use crate::core::statement::{ALGORITHM, KEY_BYTES, PublishedKey, PublishedKeys, StatementKey};
use crate::store;

/// What a key file name adds to the SQLite database's.
pub const KEY_FILE_SUFFIX: &str = ".signing-key";

/// Where the secret key lives.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum KeySource {
    /// A key file, made on first need.
    File(PathBuf),
    /// No file: a key of this process's own, made on first need and lost at exit.
    Process,
}

impl KeySource {
    /// Where a hub on `pool` keeps its key unless told: beside a SQLite database file.
    pub fn beside(pool: &store::Pool) -> KeySource {
        match store::statements::database_file(pool) {
            Some(db) => {
                KeySource::File(PathBuf::from(format!("{}{KEY_FILE_SUFFIX}", db.display())))
            }
            None => KeySource::Process,
        }
    }

    /// Where the key is, for messages and the audit log.
    pub fn describe(&self) -> String {
        match self {
            KeySource::File(path) => format!("key file {}", path.display()),
            KeySource::Process => "this process only (no key file)".to_owned(),
        }
    }
}

/// The key this process signs with, and the hub it signs as.
#[derive(Debug)]
pub struct Signer {
    source: KeySource,
    /// The hub's public URL, as statements name it.
    public_url: Option<String>,
    /// The key last read or made; checked against the listing before each statement.
    current: Mutex<Option<Arc<StatementKey>>>,
}

/// A hub signs with the key beside its SQLite database (or, on PostgreSQL, one of this
/// process's own) unless it was given a key file ([`with_signing`]).
impl crate::Kept for Signer {
    fn make(hub: &Hub) -> Self {
        Signer::new(KeySource::beside(hub.pool()), None)
    }
}

impl Signer {
    pub fn new(source: KeySource, public_url: Option<String>) -> Signer {
        Signer {
            source,
            public_url,
            current: Mutex::new(None),
        }
    }

    pub fn source(&self) -> &KeySource {
        &self.source
    }

    pub fn public_url(&self) -> Option<&str> {
        self.public_url.as_deref()
    }

    fn cached(&self) -> Option<Arc<StatementKey>> {
        self.current
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .clone()
    }

    fn remember(&self, key: Arc<StatementKey>) {
        *self.current.lock().unwrap_or_else(|p| p.into_inner()) = Some(key);
    }
}

/// The text of a key file holding `key`.
fn key_file_text(key: &StatementKey) -> String {
    format!(
        "# enact-hub statement signing key {}: an Ed25519 secret key (base64 of its 32-byte \
         seed).\n# Keep it secret and out of shared backups; its public key is listed at \
         /api/v1/keys.\n{}\n",
        key.keyid(),
        STANDARD.encode(key.secret())
    )
}

/// Reads the key file at `path`; `None` when there is none.
fn read_key_file(path: &Path) -> Result<Option<StatementKey>, AppError> {
    let text = match std::fs::read_to_string(path) {
        Ok(text) => text,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(e) => {
            return Err(AppError::internal(format!(
                "cannot read the signing key file {}: {e}",
                path.display()
            )));
        }
    };
    warn_if_readable_by_others(path);
    let mut lines = text
        .lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty() && !l.trim_start().starts_with('#'));
    let Some((number, line)) = lines.next() else {
        return Err(AppError::internal(format!(
            "the signing key file {} holds no key (a line of base64); remove it to have a new \
             key made",
            path.display()
        )));
    };
    let bad = |why: String| {
        AppError::internal(format!(
            "the signing key file {}, line {}: {why}",
            path.display(),
            number + 1
        ))
    };
    let bytes = STANDARD
        .decode(line.trim())
        .map_err(|e| bad(format!("not base64: {e}")))?;
    let secret: [u8; KEY_BYTES] = bytes.as_slice().try_into().map_err(|_| {
        bad(format!(
            "{} bytes; an Ed25519 secret key is {KEY_BYTES}",
            bytes.len()
        ))
    })?;
    if lines.next().is_some() {
        return Err(bad("more than one key line".to_owned()));
    }
    Ok(Some(StatementKey::from_secret(&secret)))
}

#[cfg(unix)]
fn warn_if_readable_by_others(path: &Path) {
    use std::os::unix::fs::PermissionsExt;
    if let Ok(meta) = std::fs::metadata(path)
        && meta.permissions().mode() & 0o077 != 0
    {
        tracing::warn!(
            file = %path.display(),
            mode = format!("{:o}", meta.permissions().mode() & 0o777),
            "the signing key file can be read by other users: chmod 600 it"
        );
    }
}

#[cfg(not(unix))]
fn warn_if_readable_by_others(_path: &Path) {}

/// Writes `key` to a new file beside `path` that only its owner may read, and returns it.
fn write_private_file(path: &Path, key: &StatementKey) -> Result<PathBuf, AppError> {
    let temporary = PathBuf::from(format!(
        "{}.{:016x}.partial",
        path.display(),
        rand::random::<u64>()
    ));
    let written = (|| {
        let mut options = std::fs::OpenOptions::new();
        options.write(true).create_new(true);
        #[cfg(unix)]
        {
            use std::os::unix::fs::OpenOptionsExt;
            options.mode(0o600);
        }
        let mut file = options.open(&temporary)?;
        file.write_all(key_file_text(key).as_bytes())?;
        file.sync_all()
    })();
    written.map_err(|e| {
        let _ = std::fs::remove_file(&temporary);
        AppError::internal(format!(
            "cannot write the signing key file {}: {e}",
            temporary.display()
        ))
    })?;
    Ok(temporary)
}

/// The key in the file at `path`, made and written there first when there is none. Two
/// processes making it at once agree on one: the file appears whole (a hard link of a written
/// file) or not at all, and the one that finds it there reads it.
fn read_or_make_key_file(path: &Path) -> Result<(StatementKey, bool), AppError> {
    if let Some(key) = read_key_file(path)? {
        return Ok((key, false));
    }
    let key = StatementKey::from_secret(&rand::random());
    let temporary = write_private_file(path, &key)?;
    let linked = std::fs::hard_link(&temporary, path);
    let _ = std::fs::remove_file(&temporary);
    match linked {
        Ok(()) => Ok((key, true)),
        Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {
            let key = read_key_file(path)?.ok_or_else(|| {
                AppError::internal(format!("the signing key file {} vanished", path.display()))
            })?;
            Ok((key, false))
        }
        Err(e) => Err(AppError::internal(format!(
            "cannot create the signing key file {}: {e}",
            path.display()
        ))),
    }
}

/// Puts `key` in the file at `path` in place of what it held (a rename: whole or not at all).
fn replace_key_file(path: &Path, key: &StatementKey) -> Result<(), AppError> {
    let temporary = write_private_file(path, key)?;
    std::fs::rename(&temporary, path).map_err(|e| {
        let _ = std::fs::remove_file(&temporary);
        AppError::internal(format!(
            "cannot replace the signing key file {}: {e}",
            path.display()
        ))
    })
}

/// The key to sign with now, inside `conn`'s transaction: the one in use while it is listed
/// and not retired; otherwise the key file's (read again: another process may have rotated
/// it), made when there is none; a key not yet listed is listed (audited as `key.generate`).
pub(crate) async fn signing_key(
    hub: &Hub,
    conn: &mut store::Tx,
) -> Result<Arc<StatementKey>, AppError> {
    let signer = &hub.kept::<Signer>();
    if let Some(key) = signer.cached() {
        match store::statements::key(conn, &key.keyid()).await? {
            Some(row) if row.retired_at.is_none() => return Ok(key),
            Some(_) => {} // rotated away elsewhere: read the file again
            None => {
                // Listed once, but the database was restored or replaced beneath us.
                list_key(
                    conn,
                    &key,
                    &format!("{} (in use)", signer.source.describe()),
                )
                .await?;
                return Ok(key);
            }
        }
    }
    let (key, made) = match &signer.source {
        KeySource::File(path) => read_or_make_key_file(path)?,
        KeySource::Process => (StatementKey::from_secret(&rand::random()), true),
    };
    let keyid = key.keyid();
    match store::statements::key(conn, &keyid).await? {
        Some(row) if row.retired_at.is_some() => {
            return Err(AppError::internal(format!(
                "the signing key in {} (key {keyid}) was retired at {}: a retired key signs \
                 nothing; run `enact-hub keys rotate` to make a new one, or remove the file",
                signer.source.describe(),
                row.retired_at.unwrap_or_default()
            )));
        }
        Some(_) => {}
        None => {
            let how = if made { "made" } else { "read" };
            list_key(conn, &key, &format!("{how}: {}", signer.source.describe())).await?;
        }
    }
    let key = Arc::new(key);
    signer.remember(key.clone());
    Ok(key)
}

/// Lists `key`'s public half, audited as `key.generate` when it is new.
async fn list_key(conn: &mut store::Tx, key: &StatementKey, detail: &str) -> Result<(), AppError> {
    let keyid = key.keyid();
    let public = STANDARD.encode(key.public_key());
    if store::statements::insert_key(conn, &keyid, ALGORITHM, &public).await? {
        audit::record(
            conn,
            &Actor::Server,
            AuditAction::KeyGenerate,
            format!("key {keyid}"),
            None,
            detail,
        )
        .await?;
        tracing::info!(keyid = %keyid, "statement signing key listed ({detail})");
    }
    Ok(())
}

/// The key this process signs with, made and listed when there is none yet (a server calls
/// this at start, so a misplaced or retired key file stops it there rather than at the first
/// submission).
pub async fn prepare(hub: &Hub) -> Result<PublishedKey, AppError> {
    let mut tx = hub.write(Lane::Interactive).await?;
    let key = signing_key(hub, &mut tx).await?;
    let row = store::statements::key(&mut tx, &key.keyid())
        .await?
        .ok_or_else(|| AppError::internal("a signing key just listed is not listed"))?;
    tx.commit().await?;
    Ok(published(row))
}

/// Where this process's key lives.
pub fn source(hub: &Hub) -> KeySource {
    hub.kept::<Signer>().source().clone()
}

/// The hub signing its statements with the key in `key_file` (made there on first need)
/// instead of the one beside a SQLite database (`--signing-key`, `ENACT_HUB_SIGNING_KEY`),
/// naming itself by `public_url` in them (`--public-url`, `ENACT_HUB_PUBLIC_URL`).
pub fn with_signing(hub: Hub, key_file: Option<PathBuf>, public_url: Option<String>) -> Hub {
    let source = match key_file {
        Some(path) => KeySource::File(path),
        None => KeySource::beside(hub.pool()),
    };
    hub.with_kept(Signer::new(source, public_url))
}

fn published(row: store::statements::KeyRow) -> PublishedKey {
    PublishedKey {
        keyid: row.keyid,
        algorithm: row.algorithm,
        public_key: row.public_key,
        created_at: row.created_at,
        retired_at: row.retired_at,
    }
}

/// Every public key the hub signed with, oldest first (`GET /api/v1/keys`).
pub async fn public_keys(hub: &Hub) -> Result<PublishedKeys, AppError> {
    let mut conn = hub.conn().await?;
    let rows = store::statements::keys(&mut conn).await?;
    Ok(PublishedKeys {
        keys: rows.into_iter().map(published).collect(),
    })
}

/// What a rotation did.
#[derive(Debug, Clone)]
pub struct Rotated {
    /// The new key, which signs from now on.
    pub key: PublishedKey,
    /// The keys it retired (they stay listed, to verify what they signed).
    pub retired: Vec<String>,
    /// Where the new secret is.
    pub source: KeySource,
}

/// Replaces the signing key: a new secret in the key file (or this process, without one), its
/// public key listed, every other key retired, audited as `key.rotate` by `actor`. Old
/// statements keep verifying against the listed keys; new ones use the new key, in every
/// process on the database (each reads the file again when it sees its key retired).
///
/// The file is written before the listing commits: if the commit fails, the file's new key is
/// listed by whichever process signs next, and the old one stays current alongside it.
pub async fn rotate(hub: &Hub, actor: &Actor) -> Result<Rotated, AppError> {
    let key = StatementKey::from_secret(&rand::random());
    let keyid = key.keyid();
    let source = hub.kept::<Signer>().source.clone();
    let mut tx = hub.write(Lane::Interactive).await?;
    if let KeySource::File(path) = &source {
        replace_key_file(path, &key)?;
    }
    store::statements::insert_key(
        &mut tx,
        &keyid,
        ALGORITHM,
        &STANDARD.encode(key.public_key()),
    )
    .await?;
    let retired = store::statements::retire_all_but(&mut tx, &keyid).await?;
    audit::record(
        &mut tx,
        actor,
        AuditAction::KeyRotate,
        format!("key {keyid}"),
        None,
        format!(
            "new key in {}; retired: {}",
            source.describe(),
            if retired.is_empty() {
                "none".to_owned()
            } else {
                retired.join(", ")
            }
        ),
    )
    .await?;
    let row = store::statements::key(&mut tx, &keyid)
        .await?
        .ok_or_else(|| AppError::internal("a signing key just listed is not listed"))?;
    tx.commit().await?;
    hub.kept::<Signer>().remember(Arc::new(key));
    tracing::info!(keyid = %keyid, retired = ?retired, "statement signing key rotated");
    Ok(Rotated {
        key: published(row),
        retired,
        source,
    })
}

/// [`rotate`] from the command line: refused without a key file, since a key of this process
/// only would be lost when the command ends and never sign anything.
pub async fn rotate_key_file(hub: &Hub, actor: &Actor) -> Result<Rotated, AppError> {
    if hub.kept::<Signer>().source == KeySource::Process {
        return Err(AppError::Invalid(
            "this database keeps no key file beside it (PostgreSQL): give --signing-key FILE \
             (or ENACT_HUB_SIGNING_KEY), the file the servers sign with"
                .to_owned(),
        ));
    }
    rotate(hub, actor).await
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_key_file_is_made_once_and_read_back() {
        let dir = tempfile::tempdir().expect("tempdir");
        let path = dir.path().join("hub.db.signing-key");
        let (made, new) = read_or_make_key_file(&path).expect("made");
        assert!(new);
        let (read, new) = read_or_make_key_file(&path).expect("read");
        assert!(!new);
        assert_eq!(made.keyid(), read.keyid());
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt;
            let mode = std::fs::metadata(&path).expect("meta").permissions().mode();
            assert_eq!(mode & 0o777, 0o600);
        }
        let other = StatementKey::from_secret(&[9; KEY_BYTES]);
        replace_key_file(&path, &other).expect("replaced");
        assert_eq!(
            read_key_file(&path).expect("read").expect("a key").keyid(),
            other.keyid()
        );
        let leftovers = std::fs::read_dir(dir.path()).expect("dir").count();
        assert_eq!(leftovers, 1, "no temporary file is left behind");
    }

    #[test]
    fn a_broken_key_file_says_where() {
        let dir = tempfile::tempdir().expect("tempdir");
        let path = dir.path().join("k");
        std::fs::write(&path, "# comment\n\nnot base64!\n").expect("write");
        let e = read_key_file(&path).expect_err("refused");
        let AppError::Internal(e) = e else {
            panic!("not internal: {e}")
        };
        let text = e.to_string();
        assert!(text.contains("line 3: not base64"), "{text}");
        std::fs::write(&path, format!("{}\n", STANDARD.encode([1u8; 16]))).expect("write");
        let e = read_key_file(&path).expect_err("short");
        assert!(format!("{e:?}").contains("16 bytes"), "{e:?}");
    }
}
