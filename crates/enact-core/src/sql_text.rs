//! The benchmark's enums as TEXT columns, for the store (only with the `sqlx` feature, which
//! the hub turns on). Each maps through its `as_str` and `parse`, so rows carry the enum and a
//! column's CHECK constraint stays the one list of spellings on disk. This is the one place the
//! core names the database crate: Rust lets a trait be implemented only beside the trait or
//! the type, and the types are the benchmark's. Nothing here runs a query.

/// Implements `sqlx::Type`, `Encode` and `Decode` for SQLite and PostgreSQL on each type,
/// through its `as_str` and `parse` (also used by the store for its own enums).
#[macro_export]
macro_rules! text_columns {
    ($($ty:ty),* $(,)?) => {$(
        $crate::text_columns!(@in $crate::sql_text::sqlx::Sqlite, $ty);
        $crate::text_columns!(@in $crate::sql_text::sqlx::Postgres, $ty);
    )*};
    (@in $db:ty, $ty:ty) => {
        impl $crate::sql_text::sqlx::Type<$db> for $ty {
            fn type_info() -> <$db as $crate::sql_text::sqlx::Database>::TypeInfo {
                <str as $crate::sql_text::sqlx::Type<$db>>::type_info()
            }

            fn compatible(ty: &<$db as $crate::sql_text::sqlx::Database>::TypeInfo) -> bool {
                <str as $crate::sql_text::sqlx::Type<$db>>::compatible(ty)
            }
        }

        impl<'q> $crate::sql_text::sqlx::Encode<'q, $db> for $ty {
            fn encode_by_ref(
                &self,
                buf: &mut <$db as $crate::sql_text::sqlx::Database>::ArgumentBuffer<'q>,
            ) -> Result<$crate::sql_text::sqlx::encode::IsNull, $crate::sql_text::sqlx::error::BoxDynError> {
                let text: &'static str = self.as_str();
                <&str as $crate::sql_text::sqlx::Encode<'q, $db>>::encode(text, buf)
            }
        }

        impl<'r> $crate::sql_text::sqlx::Decode<'r, $db> for $ty {
            fn decode(
                value: <$db as $crate::sql_text::sqlx::Database>::ValueRef<'r>,
            ) -> Result<Self, $crate::sql_text::sqlx::error::BoxDynError> {
                let text = <&str as $crate::sql_text::sqlx::Decode<'r, $db>>::decode(value)?;
                <$ty>::parse(text).ok_or_else(|| {
                    format!("unknown {} {text:?}", stringify!($ty)).into()
                })
            }
        }
    };
}

/// The database crate, for the macro's expansions in other crates.
pub use sqlx;

text_columns!(
    crate::agreement::protocol::AssignmentKind,
    crate::annotation::OutcomeKind,
    crate::credentials::Role,
    crate::dataset::AnswerVisibility,
    crate::semantics::SignatureSource,
    crate::submission::SubmissionStatus,
    crate::submission::VerdictOutcome,
    crate::submission::Visibility,
    crate::submission::Provenance,
    crate::verifier::ScoringPolicy,
);
