//! The changes processes on one database announce to each other, and their payloads: server
//! instances on PostgreSQL with `NOTIFY` ([`super::watch::listen`]); on either database the
//! command line to running servers, and on SQLite every process, through the change feed
//! table ([`super::watch::follow_feed`]).

/// The `LISTEN`/`NOTIFY` channel instances announce changes on.
pub const CHANNEL: &str = "enact_hub_changes";

/// A fresh name for this process in the change feed (random, so two processes started in the
/// same instant still differ).
pub fn new_origin() -> String {
    format!("{:016x}", rand::random::<u64>())
}

/// A change other instances must drop from their caches.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Change {
    /// An annotator's draft, answer, skip or flag of an item.
    Standing { annotator: i64, item: i64 },
    /// A submission or an answer changed what a leaderboard shows.
    Boards,
    /// A login session ended (its token's hash).
    SessionEnded(String),
    /// Anything may have changed (sent to local subscribers after missed notifications; never
    /// announced).
    Everything,
}

impl Change {
    /// The `NOTIFY` payload: `standing 3 17`, `boards`, `session <hash>`.
    pub fn payload(&self) -> String {
        match self {
            Change::Standing { annotator, item } => format!("standing {annotator} {item}"),
            Change::Boards => "boards".to_owned(),
            Change::SessionEnded(hash) => format!("session {hash}"),
            Change::Everything => "everything".to_owned(),
        }
    }

    pub fn parse(payload: &str) -> Option<Change> {
        let mut words = payload.split(' ');
        let change = match (words.next()?, words.next(), words.next()) {
            ("standing", Some(a), Some(i)) => Change::Standing {
                annotator: a.parse().ok()?,
                item: i.parse().ok()?,
            },
            ("boards", None, None) => Change::Boards,
            ("session", Some(hash), None) => Change::SessionEnded(hash.to_owned()),
            ("everything", None, None) => Change::Everything,
            _ => return None,
        };
        words.next().is_none().then_some(change)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn payloads_read_back_as_the_change_and_nothing_else_is_read() {
        for change in [
            Change::Standing {
                annotator: 3,
                item: 17,
            },
            Change::Boards,
            Change::SessionEnded("ab12".to_owned()),
            Change::Everything,
        ] {
            assert_eq!(Change::parse(&change.payload()), Some(change));
        }
        for bad in [
            "",
            "standing 3",
            "standing x 4",
            "standing 3 4 5",
            "boards now",
            "session",
            "session a b",
            "sessions a",
        ] {
            assert_eq!(Change::parse(bad), None, "{bad:?}");
        }
    }
}
