//! Where key frames' PNG bytes live: in the database (the default) or in an object store
//! (`s3://`, `gs://`, `az://`, `file:///dir`), content-addressed by SHA-256 as in the database.
//!
//! The database always keeps each frame's row (hash, width, height). Its `png` column holds
//! the bytes, or nothing (an empty blob, which no PNG is) when they are in an object store;
//! each row says where its bytes are, so a server reads correctly in the middle of a
//! `frames migrate` as well as after it.

use std::sync::Arc;
use std::time::{Duration, Instant};

use bytes::Bytes;
use object_store::path::Path as ObjectPath;
use object_store::signer::Signer;
use object_store::{Attribute, Attributes, ObjectStore, PutOptions, PutPayload};
use sha2::{Digest, Sha256};

use super::refusal::Refusal;
use super::{AppError, Hub};
use crate::Lane;
use crate::store;

/// What `--frames` names when the bytes stay in the database.
pub const DATABASE: &str = "database";

/// Frames held in an object store.
pub struct ObjectFrames {
    /// The URL as given, for messages.
    url: String,
    store: Arc<dyn ObjectStore>,
    prefix: ObjectPath,
    /// Presigns GET URLs (S3, GCS and Azure can); `None` for a local folder.
    signer: Option<Arc<dyn Signer>>,
    /// Whether objects carry a content type and cache headers (a local folder keeps none and
    /// refuses to be given some).
    keeps_attributes: bool,
}

/// An opened object store, and what signs its URLs when it can.
type Opened = (Arc<dyn ObjectStore>, Option<Arc<dyn Signer>>);

/// Where frame bytes are written, and read when a row does not hold them.
#[derive(Clone, Default)]
pub enum FrameStore {
    #[default]
    Database,
    Objects(Arc<ObjectFrames>),
}

impl std::fmt::Debug for FrameStore {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.describe())
    }
}

/// An object store that failed: which one, doing what, and its error.
fn storage_error(url: &str, doing: &str, e: impl std::fmt::Display) -> AppError {
    AppError::Unavailable(format!("frame storage {url}: {doing} failed: {e}"))
}

impl FrameStore {
    /// `database`, or an object store URL: `s3://bucket/prefix`, `gs://bucket/prefix`,
    /// `az://container/prefix`, `file:///absolute/dir`. Credentials, region and endpoint come
    /// from the environment as each cloud's own tools read them (`AWS_ACCESS_KEY_ID`,
    /// `AWS_ENDPOINT`, `AWS_ALLOW_HTTP`, `GOOGLE_SERVICE_ACCOUNT`, `AZURE_STORAGE_ACCOUNT_NAME`,
    /// ...). A folder is created if missing.
    pub fn parse(spec: &str) -> Result<FrameStore, AppError> {
        if spec == DATABASE {
            return Ok(FrameStore::Database);
        }
        let bad = |why: String| {
            AppError::Invalid(format!(
                "--frames {spec:?}: {why} (expected `database`, s3://bucket/prefix, \
                 gs://bucket/prefix, az://container/prefix or file:///dir)"
            ))
        };
        let url = url::Url::parse(spec).map_err(|e| bad(e.to_string()))?;
        let build = |e: object_store::Error| bad(e.to_string());
        // A cloud store both stores and signs URLs.
        fn signing<S: ObjectStore + Signer>(store: S) -> Opened {
            let store = Arc::new(store);
            (store.clone(), Some(store))
        }
        let ((store, signer), prefix): (Opened, &str) = match url.scheme() {
            "s3" | "s3a" => (
                signing(
                    object_store::aws::AmazonS3Builder::from_env()
                        .with_url(spec)
                        .build()
                        .map_err(build)?,
                ),
                url.path(),
            ),
            "gs" => (
                signing(
                    object_store::gcp::GoogleCloudStorageBuilder::from_env()
                        .with_url(spec)
                        .build()
                        .map_err(build)?,
                ),
                url.path(),
            ),
            "az" | "azure" | "abfs" | "abfss" => (
                signing(
                    object_store::azure::MicrosoftAzureBuilder::from_env()
                        .with_url(spec)
                        .build()
                        .map_err(build)?,
                ),
                url.path(),
            ),
            "file" => {
                let dir = url
                    .to_file_path()
                    .map_err(|()| bad("not an absolute local path".into()))?;
                std::fs::create_dir_all(&dir)
                    .map_err(|e| bad(format!("cannot create {}: {e}", dir.display())))?;
                let local = object_store::local::LocalFileSystem::new_with_prefix(&dir)
                    .map_err(build)?
                    .with_automatic_cleanup(true);
                ((Arc::new(local), None), "")
            }
            other => return Err(bad(format!("unknown scheme {other:?}"))),
        };
        let prefix = ObjectPath::parse(prefix.trim_matches('/'))
            .map_err(|e| bad(format!("bad prefix: {e}")))?;
        Ok(FrameStore::Objects(Arc::new(ObjectFrames {
            url: spec.trim_end_matches('/').to_owned(),
            store,
            prefix,
            keeps_attributes: signer.is_some(),
            signer,
        })))
    }

    /// `database` or the object store's URL.
    pub fn describe(&self) -> &str {
        match self {
            FrameStore::Database => DATABASE,
            FrameStore::Objects(objects) => &objects.url,
        }
    }

    pub fn objects(&self) -> Option<&Arc<ObjectFrames>> {
        match self {
            FrameStore::Database => None,
            FrameStore::Objects(objects) => Some(objects),
        }
    }
}

impl ObjectFrames {
    /// `prefix/ab/abcdef….png`: two hex digits of fan-out keep a local folder's directories
    /// small at millions of frames.
    fn key(&self, sha256: &str) -> ObjectPath {
        let fan_out = sha256.get(..2).unwrap_or("00");
        self.prefix
            .child(fan_out)
            .child(format!("{sha256}.png").as_str())
    }

    pub fn url(&self) -> &str {
        &self.url
    }

    /// Stores a frame's bytes under its hash (idempotent: the same hash is the same bytes),
    /// typed and cacheable for clients that a presigned redirect sends to the store.
    pub async fn put(&self, sha256: &str, png: Bytes) -> Result<(), AppError> {
        let mut attributes = Attributes::new();
        if self.keeps_attributes {
            attributes.insert(Attribute::ContentType, "image/png".into());
            attributes.insert(
                Attribute::CacheControl,
                "public, max-age=31536000, immutable".into(),
            );
        }
        let options = PutOptions {
            attributes,
            ..PutOptions::default()
        };
        self.store
            .put_opts(&self.key(sha256), PutPayload::from(png), options)
            .await
            .map_err(|e| storage_error(&self.url, &format!("writing frame {sha256}"), e))?;
        Ok(())
    }

    /// A frame's bytes, `None` when the store has no such object.
    pub async fn get(&self, sha256: &str) -> Result<Option<Bytes>, AppError> {
        let doing = || format!("reading frame {sha256}");
        match self.store.get(&self.key(sha256)).await {
            Ok(found) => Ok(Some(
                found
                    .bytes()
                    .await
                    .map_err(|e| storage_error(&self.url, &doing(), e))?,
            )),
            Err(object_store::Error::NotFound { .. }) => Ok(None),
            Err(e) => Err(storage_error(&self.url, &doing(), e)),
        }
    }

    /// Whether the store holds the frame.
    pub async fn contains(&self, sha256: &str) -> Result<bool, AppError> {
        match self.store.head(&self.key(sha256)).await {
            Ok(_) => Ok(true),
            Err(object_store::Error::NotFound { .. }) => Ok(false),
            Err(e) => Err(storage_error(
                &self.url,
                &format!("looking up frame {sha256}"),
                e,
            )),
        }
    }

    /// A URL that lets anyone GET the frame for `expires_in`, when the store can sign one.
    pub async fn signed_url(
        &self,
        sha256: &str,
        expires_in: Duration,
    ) -> Option<Result<url::Url, AppError>> {
        let signer = self.signer.as_ref()?;
        Some(
            signer
                .signed_url(http::Method::GET, &self.key(sha256), expires_in)
                .await
                .map_err(|e| storage_error(&self.url, &format!("signing frame {sha256}"), e)),
        )
    }

    /// A frame that must be in the store: its bytes, checked against the hash.
    async fn get_checked(&self, sha256: &str) -> Result<Bytes, AppError> {
        let png = self.get(sha256).await?.ok_or_else(|| {
            AppError::NotFound(format!("frame {sha256} is missing from {}", self.url))
        })?;
        if hex::encode(Sha256::digest(&png)) != sha256 {
            return Err(AppError::Conflict(format!(
                "frame {sha256} in {} holds other bytes (their hash differs)",
                self.url
            )));
        }
        Ok(png)
    }
}

/// Where a frame's bytes are for a reader.
pub enum FrameBytes {
    /// Read (from the cache, the database or the object store).
    Png(Bytes),
    /// In an object store that can sign URLs: where to send the client.
    Redirect(url::Url),
}

/// A frame's PNG bytes by content hash, from the database or the object store its row
/// points to, or a 404 that names the hash.
pub async fn png(hub: &Hub, sha256: &str) -> Result<Bytes, AppError> {
    match png_or_redirect(hub, sha256, None).await? {
        FrameBytes::Png(png) => Ok(png),
        // Only asked for with a redirect.
        FrameBytes::Redirect(_) => Err(AppError::internal("a frame redirect nobody asked for")),
    }
}

/// [`png`], or for a frame held in an object store that signs URLs and with `redirect` set,
/// a URL valid for `redirect` instead of the bytes (which are then not read).
pub async fn png_or_redirect(
    hub: &Hub,
    sha256: &str,
    redirect: Option<Duration>,
) -> Result<FrameBytes, AppError> {
    if let Some(png) = hub.frames.get(sha256) {
        return Ok(FrameBytes::Png(png));
    }
    let held = {
        let mut conn = hub.conn().await?;
        store::frames::png(&mut conn, sha256).await?
    };
    let png = match held {
        None => {
            return Err(Refusal::NoFrame {
                frame: sha256.to_owned(),
            }
            .into());
        }
        Some(Some(png)) => Bytes::from(png),
        Some(None) => {
            let signed = match (redirect, hub.frame_store.objects()) {
                (Some(expires), Some(objects)) => objects.signed_url(sha256, expires).await,
                _ => None,
            };
            if let Some(url) = signed {
                return Ok(FrameBytes::Redirect(url?));
            }
            object_bytes(hub, sha256).await?
        }
    };
    hub.frames.insert(sha256, png.clone());
    Ok(FrameBytes::Png(png))
}

/// The origin (`https://host:port`) of the presigned URLs frame requests are redirected to,
/// when they are: pages must allow images from it.
pub async fn redirect_origin(hub: &Hub) -> Option<String> {
    let expires = hub.frame_redirect?;
    let objects = hub.frame_store.objects()?;
    match objects.signed_url(&"0".repeat(64), expires).await? {
        Ok(url) => Some(url.origin().ascii_serialization()),
        Err(e) => {
            tracing::warn!(error = %e, "cannot sign a frame URL; frame requests will fail");
            None
        }
    }
}

/// The bytes of a frame whose row says they are in the object store.
pub async fn object_bytes(hub: &Hub, sha256: &str) -> Result<Bytes, AppError> {
    let Some(objects) = hub.frame_store.objects() else {
        return Err(AppError::Unavailable(format!(
            "frame {sha256} is held in object storage, and this process has none configured \
             (its operator names the store in ENACT_HUB_FRAMES)"
        )));
    };
    objects.get(sha256).await?.ok_or_else(|| {
        AppError::Unavailable(format!(
            "frame {sha256} is missing from {}: the database says it was moved there",
            objects.url
        ))
    })
}

/// How many frames hold their bytes in the database, and how many in object storage.
pub async fn count_by_place(hub: &Hub) -> Result<(u64, u64), AppError> {
    let mut conn = hub.conn().await?;
    Ok(store::frames::count_by_place(&mut conn).await?)
}

/// Counts from [`migrate`].
#[derive(Debug, Default, Clone, serde::Serialize)]
pub struct MigrateReport {
    /// Frames whose bytes were moved.
    pub moved: u64,
    /// Their bytes.
    pub bytes: u64,
    /// Frames already where they were to go.
    pub already_there: u64,
    pub seconds: f64,
}

/// Frames moved per transaction: an interrupted migration loses at most one batch's work,
/// and the next run carries on from the rows not yet moved.
const MIGRATE_BATCH: usize = 64;

/// Moves every frame's bytes to `to`. To an object store: frames held in the database are
/// written there and their bytes dropped from the database; frames held in `from` (another
/// object store) are copied. To [`FrameStore::Database`]: frames held in `from` are read
/// back into the database. Each batch commits on its own, so an interrupted run is resumed
/// by running it again. Bytes are checked against their hash on the way.
pub async fn migrate(
    hub: &Hub,
    from: &FrameStore,
    to: &FrameStore,
    progress: impl Fn(u64, u64),
) -> Result<MigrateReport, AppError> {
    let started = Instant::now();
    let mut report = MigrateReport::default();
    let (in_database, elsewhere) = {
        let mut conn = hub.conn().await?;
        store::frames::count_by_place(&mut conn).await?
    };
    // Another object store to read the frames held outside the database from.
    let source = from.objects().filter(|_| from.describe() != to.describe());
    if to.objects().is_none() && elsewhere > 0 && source.is_none() {
        return Err(AppError::Invalid(format!(
            "{elsewhere} frames are held in object storage; name where with --from URL"
        )));
    }
    let total = match to {
        FrameStore::Database => elsewhere,
        FrameStore::Objects(_) => in_database + elsewhere,
    };
    let mut done = 0;
    progress(done, total);

    if let Some(target) = to.objects() {
        // First the frames held outside the database: copied from `source` when the target
        // lacks them (rows do not change); without a source, they must already be in the
        // target (a migration run again).
        let mut after = 0;
        loop {
            let batch = {
                let mut conn = hub.conn().await?;
                store::frames::held_elsewhere(&mut conn, after, MIGRATE_BATCH).await?
            };
            let Some((last, _)) = batch.last() else { break };
            after = *last;
            let mut copies = Vec::new();
            for (_, sha256) in &batch {
                if target.contains(sha256).await? {
                    report.already_there += 1;
                } else if let Some(source) = source {
                    copies.push((sha256.clone(), source.get_checked(sha256).await?));
                } else {
                    return Err(AppError::Invalid(format!(
                        "frame {sha256} is held in object storage but not in {}; name where \
                         the frames are with --from URL",
                        target.url
                    )));
                }
            }
            report.moved += copies.len() as u64;
            report.bytes += copies.iter().map(|(_, png)| png.len() as u64).sum::<u64>();
            put_all(target, copies.into_iter()).await?;
            done += batch.len() as u64;
            progress(done, total);
        }
        // Then out of the database, batch by batch: rows still holding bytes are what remains.
        loop {
            let batch = {
                let mut conn = hub.conn().await?;
                store::frames::held_in_database(&mut conn, MIGRATE_BATCH).await?
            };
            if batch.is_empty() {
                break;
            }
            for (sha256, png) in &batch {
                if hex::encode(Sha256::digest(png)) != *sha256 {
                    return Err(AppError::Conflict(format!(
                        "frame {sha256} in the database holds other bytes (their hash \
                         differs); nothing of it was moved"
                    )));
                }
            }
            put_all(
                target,
                batch
                    .iter()
                    .map(|(sha, png)| (sha.clone(), Bytes::copy_from_slice(png))),
            )
            .await?;
            let hashes: Vec<&str> = batch.iter().map(|(sha, _)| sha.as_str()).collect();
            let mut tx = hub.write(Lane::Bulk).await?;
            store::frames::drop_bytes(&mut tx, &hashes).await?;
            tx.commit().await?;
            report.moved += batch.len() as u64;
            report.bytes += batch.iter().map(|(_, png)| png.len() as u64).sum::<u64>();
            done += batch.len() as u64;
            progress(done, total);
        }
    } else if let Some(source) = source {
        // Back into the database.
        let mut after = 0;
        loop {
            let batch = {
                let mut conn = hub.conn().await?;
                store::frames::held_elsewhere(&mut conn, after, MIGRATE_BATCH).await?
            };
            let Some((last, _)) = batch.last() else { break };
            after = *last;
            let mut read = Vec::with_capacity(batch.len());
            for (_, sha256) in &batch {
                read.push((sha256.as_str(), source.get_checked(sha256).await?));
            }
            let mut tx = hub.write(Lane::Bulk).await?;
            for (sha256, png) in &read {
                store::frames::restore_bytes(&mut tx, sha256, png).await?;
            }
            tx.commit().await?;
            report.moved += read.len() as u64;
            report.bytes += read.iter().map(|(_, png)| png.len() as u64).sum::<u64>();
            done += read.len() as u64;
            progress(done, total);
        }
    }
    report.seconds = started.elapsed().as_secs_f64();
    Ok(report)
}

/// Frames written to the store at once (object stores answer each write after a round trip).
pub const PUTS_IN_FLIGHT: usize = 16;

/// Writes frames to `target`, [`PUTS_IN_FLIGHT`] at a time.
pub async fn put_all(
    target: &Arc<ObjectFrames>,
    frames: impl Iterator<Item = (String, Bytes)>,
) -> Result<(), AppError> {
    let mut pending = tokio::task::JoinSet::new();
    for (sha256, png) in frames {
        if pending.len() >= PUTS_IN_FLIGHT
            && let Some(done) = pending.join_next().await
        {
            done??;
        }
        let store = target.clone();
        pending.spawn(async move { store.put(&sha256, png).await });
    }
    while let Some(done) = pending.join_next().await {
        done??;
    }
    Ok(())
}
