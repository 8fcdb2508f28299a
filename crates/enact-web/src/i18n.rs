//! The pages' languages: the message catalogues (Project Fluent, one `.ftl` file per locale
//! under `locales/`, compiled into the binary), choosing a request's locale, and writing
//! numbers and dates for it.
//!
//! A request's locale is the `enact_lang` cookie if it names a locale we have (the switch sets
//! it, and logging in sets it from the annotator's saved preference), else the best match of
//! `Accept-Language` by q-value, else English. Templates look messages up through the [`Tr`]
//! field every translated page carries: `{{ tr.t("queue-title") }}`, with variables `t_n`, `t_s` and the like.
//!
//! Never translated: an item's question text and action descriptions (they are the benchmark)
//! and the JSON API's error sentences (English, beside their `code`). A page says a typed
//! refusal in its own language, from the `refusal-*` messages. `tests/service/i18n.rs` fails
//! when a key used by a template, the page script or this crate is missing from a locale, or a
//! catalogue holds a key nothing uses.

use std::sync::LazyLock;
use std::time::Duration;

use axum::extract::FromRequestParts;
use axum::http::request::Parts;
use axum::http::{HeaderMap, HeaderValue, header};
use fluent_bundle::concurrent::FluentBundle;
use fluent_bundle::{FluentArgs, FluentResource, FluentValue};

use super::AppState;
use super::cookies::cookie;
use crate::app::refusal::{Detail, Expected, ImportPathProblem, Refusal};
use crate::core::annotation::DraftProblem;

/// The cookie holding the locale a browser chose with the switch.
pub const LOCALE_COOKIE: &str = "enact_lang";

/// A locale the pages are written in. Every one in [`Locale::ALL`] is complete: each has every
/// message.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Locale {
    English,
    SimplifiedChinese,
    /// A pseudo-locale for layout checks, never offered to users: English wrapped in `⟦…⟧`,
    /// 40 % longer, on a right-to-left page (see [`pseudo`]). It is not in [`Locale::ALL`], so
    /// the switch, `Accept-Language` and saved preferences never choose it; only a hand-set
    /// `enact_lang=ar-XB` cookie does (the tag is the one Chromium and Android give their
    /// right-to-left pseudo-locale).
    PseudoRtl,
}

impl Locale {
    pub const ALL: [Locale; 2] = [Locale::English, Locale::SimplifiedChinese];

    /// The BCP 47 tag: the `lang` attribute, the cookie's value, the stored preference.
    pub fn tag(self) -> &'static str {
        match self {
            Locale::English => "en",
            Locale::SimplifiedChinese => "zh-CN",
            Locale::PseudoRtl => "ar-XB",
        }
    }

    /// The direction its pages are written in: the `dir` attribute.
    pub fn direction(self) -> &'static str {
        match self {
            Locale::English | Locale::SimplifiedChinese => "ltr",
            Locale::PseudoRtl => "rtl",
        }
    }

    /// The locale's own name for itself, as the switch shows it.
    pub fn native_name(self) -> &'static str {
        match self {
            Locale::English => "English",
            Locale::SimplifiedChinese => "简体中文",
            Locale::PseudoRtl => "⟦pseudo⟧",
        }
    }

    /// The catalogue's source, embedded so that an installed binary needs nothing on disk.
    /// The pseudo-locale has none of its own: its messages are made from English ones.
    pub fn catalogue_source(self) -> &'static str {
        match self {
            Locale::English | Locale::PseudoRtl => include_str!("../../../locales/en/pages.ftl"),
            Locale::SimplifiedChinese => include_str!("../../../locales/zh-CN/pages.ftl"),
        }
    }

    /// The locale a tag names exactly (case-insensitively), as a cookie or a preference holds.
    pub fn from_tag(tag: &str) -> Option<Locale> {
        Locale::ALL
            .into_iter()
            .find(|l| l.tag().eq_ignore_ascii_case(tag.trim()))
    }

    /// The locale that serves a language range of `Accept-Language`: `zh`, `zh-CN`, `zh-Hans`
    /// and `zh-Hans-CN` are Simplified Chinese; `zh-TW`/`zh-HK`/`zh-Hant` are not (we have no
    /// Traditional Chinese, and Simplified is not what those readers asked for).
    fn for_range(range: &str) -> Option<Locale> {
        let range = range.trim().to_ascii_lowercase();
        let mut subtags = range.split(['-', '_']);
        match subtags.next()? {
            "en" => Some(Locale::English),
            "zh" => {
                let rest: Vec<&str> = subtags.collect();
                let traditional = rest
                    .iter()
                    .any(|s| matches!(*s, "hant" | "tw" | "hk" | "mo"));
                (!traditional).then_some(Locale::SimplifiedChinese)
            }
            _ => None,
        }
    }

    /// The best locale for an `Accept-Language` header: the highest q-value among the ranges
    /// we serve (the earlier range on a tie), `None` when no range is one of ours.
    pub fn negotiate(accept_language: &str) -> Option<Locale> {
        let mut best: Option<(f32, Locale)> = None;
        for entry in accept_language.split(',') {
            let mut parts = entry.split(';');
            let range = parts.next().unwrap_or("");
            let q = parts
                .find_map(|p| p.trim().strip_prefix("q="))
                .map_or(Some(1.0), |q| q.trim().parse::<f32>().ok());
            // An unreadable q-value ignores the range rather than guessing its weight.
            let Some(q) = q.filter(|q| (0.0..=1.0).contains(q) && *q > 0.0) else {
                continue;
            };
            if let Some(locale) = Locale::for_range(range)
                && best.is_none_or(|(b, _)| q > b)
            {
                best = Some((q, locale));
            }
        }
        best.map(|(_, l)| l)
    }

    /// The locale of a request: the switch's cookie, else `Accept-Language`, else English.
    /// The cookie alone can also name the pseudo-locale (set by hand, as the layout test does).
    pub fn of_request(headers: &HeaderMap) -> Locale {
        cookie(headers, LOCALE_COOKIE)
            .and_then(|c| {
                Locale::from_tag(&c)
                    .or_else(|| (c.trim() == Locale::PseudoRtl.tag()).then_some(Locale::PseudoRtl))
            })
            .or_else(|| {
                headers
                    .get(header::ACCEPT_LANGUAGE)
                    .and_then(|v| v.to_str().ok())
                    .and_then(Locale::negotiate)
            })
            .unwrap_or(Locale::English)
    }
}

/// The catalogues, parsed once. A syntax error in one is a bug in this crate (the catalogue
/// test parses them), so the broken entries are dropped with a log line rather than failing.
static CATALOGUES: LazyLock<Vec<(Locale, FluentBundle<FluentResource>)>> = LazyLock::new(|| {
    Locale::ALL
        .into_iter()
        .map(|locale| {
            let resource = match FluentResource::try_new(locale.catalogue_source().to_owned()) {
                Ok(r) => r,
                Err((r, errors)) => {
                    tracing::error!(locale = locale.tag(), ?errors, "catalogue has errors");
                    r
                }
            };
            let id: unic_langid::LanguageIdentifier = locale
                .tag()
                .parse()
                .unwrap_or(unic_langid::LanguageIdentifier::default());
            let mut bundle = FluentBundle::new_concurrent(vec![id]);
            // No Unicode isolation marks around variables: the pages set `dir` themselves,
            // and the marks would end up in attribute values and copied text.
            bundle.set_use_isolating(false);
            // Numbers in messages get the locale's grouping, not Fluent's bare digits.
            bundle.set_formatter(Some(format_fluent_number));
            if let Err(errors) = bundle.add_resource(resource) {
                tracing::error!(
                    locale = locale.tag(),
                    ?errors,
                    "catalogue has duplicate keys"
                );
            }
            (locale, bundle)
        })
        .collect()
});

fn bundle(locale: Locale) -> Option<&'static FluentBundle<FluentResource>> {
    CATALOGUES
        .iter()
        .find(|(l, _)| *l == locale)
        .map(|(_, b)| b)
}

/// The message `key` of `locale` with `args`; the key itself when it is missing (the catalogue
/// test keeps that from shipping).
fn format(locale: Locale, key: &str, args: Option<&FluentArgs>) -> String {
    if locale == Locale::PseudoRtl {
        return pseudo(&format(Locale::English, key, args));
    }
    let Some(bundle) = bundle(locale) else {
        return key.to_owned();
    };
    let Some(pattern) = bundle.get_message(key).and_then(|m| m.value()) else {
        tracing::warn!(locale = locale.tag(), key, "missing message");
        return key.to_owned();
    };
    let mut errors = Vec::new();
    let text = bundle.format_pattern(pattern, args, &mut errors);
    if !errors.is_empty() {
        tracing::warn!(
            locale = locale.tag(),
            key,
            ?errors,
            "message formatting errors"
        );
    }
    text.into_owned()
}

/// The pseudo-locale's version of an English message: wrapped in `⟦…⟧` (a string that reaches
/// a page without them did not come from the catalogue) and made 40 % longer with filler words,
/// as translations into longer languages are. Filler words rather than one long run, so that
/// text wraps as real words would. `{name}` placeholders of the script's messages are kept.
pub fn pseudo(english: &str) -> String {
    const FILLER: [&str; 6] = ["ipsum", "dolor", "sit", "amet", "elit", "sed"];
    let length = english.chars().count();
    let wanted = (length * 2).div_ceil(5);
    let mut padding = String::new();
    for word in FILLER.iter().cycle() {
        if padding.chars().count() >= wanted {
            break;
        }
        padding.push(' ');
        padding.push_str(word);
    }
    format!("⟦{english}{padding}⟧")
}

/// Fluent's hook for numbers in messages: grouped, with the fraction digits the value has
/// (at most 3), as [`decimal`] writes them.
fn format_fluent_number<M>(value: &FluentValue, _memoizer: &M) -> Option<String> {
    match value {
        FluentValue::Number(n) => {
            let digits = n
                .options
                .minimum_fraction_digits
                .unwrap_or(if n.value.fract() == 0.0 { 0 } else { 3 });
            let text = decimal(n.value, digits.min(3));
            // "2.500" from a float: drop the zeros no one asked for.
            Some(
                if n.options.minimum_fraction_digits.is_none() && text.contains('.') {
                    text.trim_end_matches('0').trim_end_matches('.').to_owned()
                } else {
                    text
                },
            )
        }
        _ => None,
    }
}

/// `value` with `fraction_digits` decimals and thousands grouped: "8,972", "12.5", "-0.3".
///
/// Our own formatter rather than ICU4X's `icu_decimal`: both locales we serve write numbers
/// the same way (CLDR: decimal point ".", group separator "," every three digits, percent
/// "12.5%" with no space, for `en` and for `zh-Hans`), so this is all the CLDR data the pages
/// need; ICU4X would add its compiled data and a dozen crates to the build for it. A locale
/// with other symbols (`de`: "1.234,5") needs a branch here, which the tests below pin.
pub fn decimal(value: f64, fraction_digits: usize) -> String {
    if !value.is_finite() {
        return "–".to_owned();
    }
    let text = format!("{:.*}", fraction_digits, value.abs());
    let (whole, fraction) = match text.split_once('.') {
        Some((w, f)) => (w, Some(f)),
        None => (text.as_str(), None),
    };
    let mut grouped = String::with_capacity(whole.len() + whole.len() / 3);
    for (i, c) in whole.chars().enumerate() {
        if i > 0 && (whole.len() - i) % 3 == 0 {
            grouped.push(',');
        }
        grouped.push(c);
    }
    // No "-0.0": a value that rounds to zero has no sign.
    let negative = value < 0.0 && text.chars().any(|c| c.is_ascii_digit() && c != '0');
    let sign = if negative { "-" } else { "" };
    match fraction {
        Some(f) => format!("{sign}{grouped}.{f}"),
        None => format!("{sign}{grouped}"),
    }
}

/// The message keys of a catalogue source, in file order (for the catalogue test).
pub fn catalogue_keys(source: &str) -> Result<Vec<String>, String> {
    let resource =
        FluentResource::try_new(source.to_owned()).map_err(|(_, errors)| format!("{errors:?}"))?;
    Ok(resource
        .entries()
        .filter_map(|e| match e {
            fluent_syntax::ast::Entry::Message(m) => Some(m.id.name.to_owned()),
            _ => None,
        })
        .collect())
}

/// A count a message can take (plural rules choose the form by it).
pub trait Count {
    fn as_f64(&self) -> f64;
}

macro_rules! count_from {
    ($($t:ty),*) => {$(
        impl Count for $t {
            #[allow(clippy::cast_precision_loss)]
            fn as_f64(&self) -> f64 {
                *self as f64
            }
        }
    )*};
}
count_from!(u8, u32, u64, usize, i32, i64, f64);

// Templates pass fields by reference, sometimes twice over.
impl<T: Count + ?Sized> Count for &T {
    fn as_f64(&self) -> f64 {
        (**self).as_f64()
    }
}

fn number<'a>(n: impl Count) -> FluentValue<'a> {
    FluentValue::from(n.as_f64())
}

fn text<'a>(value: impl AsRef<str>) -> FluentValue<'a> {
    FluentValue::from(value.as_ref().to_owned())
}

/// Names a message key outside a direct lookup, so the catalogue check sees it.
pub const fn msg(key: &'static str) -> &'static str {
    key
}

/// A page's translator: what templates call to get their text in the request's locale.
#[derive(Clone, Debug)]
pub struct Tr {
    pub locale: Locale,
    /// The page's own path and query, where the language switch comes back to.
    here: String,
}

impl Tr {
    pub fn new(locale: Locale) -> Tr {
        Tr {
            locale,
            here: "/".to_owned(),
        }
    }

    /// The translator of a request: its locale, and its page for the switch to return to.
    pub fn of_request(headers: &HeaderMap, uri: &axum::http::Uri) -> Tr {
        Tr {
            locale: Locale::of_request(headers),
            here: uri
                .path_and_query()
                .map_or("/".to_owned(), |p| p.as_str().to_owned()),
        }
    }

    /// Where the language switch returns to.
    pub fn here(&self) -> &str {
        &self.here
    }

    /// The `lang` attribute of the page.
    pub fn lang(&self) -> &'static str {
        self.locale.tag()
    }

    /// The `dir` attribute of the page: the locale's writing direction.
    pub fn dir(&self) -> &'static str {
        self.locale.direction()
    }

    /// A message without variables.
    pub fn t(&self, key: &str) -> String {
        format(self.locale, key, None)
    }

    /// The message `key` with `vars` as its variables.
    fn with<'a>(
        &self,
        key: &str,
        vars: impl IntoIterator<Item = (&'a str, FluentValue<'a>)>,
    ) -> String {
        let mut args = FluentArgs::new();
        for (name, value) in vars {
            args.set(name.to_owned(), value);
        }
        format(self.locale, key, Some(&args))
    }

    /// A message with one number variable (plural rules apply to it).
    pub fn t_n(&self, key: &str, name: &str, n: impl Count) -> String {
        self.with(key, [(name, number(n))])
    }

    /// A message with one text variable.
    pub fn t_s(&self, key: &str, name: &str, value: impl AsRef<str>) -> String {
        self.with(key, [(name, text(value))])
    }

    /// A message with a number and a text variable.
    pub fn t_ns(
        &self,
        key: &str,
        n_name: &str,
        n: impl Count,
        s_name: &str,
        value: impl AsRef<str>,
    ) -> String {
        self.with(key, [(n_name, number(n)), (s_name, text(value))])
    }

    /// A message with two text variables.
    pub fn t_ss(
        &self,
        key: &str,
        a: &str,
        x: impl AsRef<str>,
        b: &str,
        y: impl AsRef<str>,
    ) -> String {
        self.with(key, [(a, text(x)), (b, text(y))])
    }

    /// A message with two number variables.
    pub fn t_nn(&self, key: &str, a: &str, x: impl Count, b: &str, y: impl Count) -> String {
        self.with(key, [(a, number(x)), (b, number(y))])
    }

    /// A message with three number variables.
    #[allow(clippy::too_many_arguments)] // name and value of each, as templates call it
    pub fn t_nnn(
        &self,
        key: &str,
        a: &str,
        x: impl Count,
        b: &str,
        y: impl Count,
        c: &str,
        z: impl Count,
    ) -> String {
        self.with(key, [(a, number(x)), (b, number(y)), (c, number(z))])
    }

    /// A message with several text variables, as the caller formatted them.
    pub fn t_args(&self, key: &str, vars: &[(&str, &str)]) -> String {
        self.with(key, vars.iter().map(|(name, value)| (*name, text(value))))
    }

    /// Why a request was refused, in the page's language.
    pub fn refusal(&self, refusal: &Refusal) -> String {
        self.with(
            refusal_key(refusal),
            refusal.details().into_iter().map(|(name, detail)| {
                let value = match detail {
                    Detail::Text(t) => FluentValue::from(t),
                    Detail::Number(n) => number(n),
                    Detail::Time(t) => FluentValue::from(self.date_time(&t)),
                };
                (name, value)
            }),
        )
    }

    /// A share (0–1) as a percentage with one decimal, without the sign: "12.5"; a dash when
    /// there is none.
    pub fn percent_figure(&self, share: Option<f64>) -> String {
        share.map_or_else(|| "–".to_owned(), |v| decimal(v * 100.0, 1))
    }

    /// A share (0–1) as a percentage with one decimal and the sign: "12.5%".
    pub fn percent(&self, share: f64) -> String {
        format!("{}%", decimal(share * 100.0, 1))
    }

    /// The day of an ISO 8601 timestamp ("2026-11-26T10:00:00Z") as the locale writes dates:
    /// "2026-11-26" in English (ISO, as the hub always showed it), "2026年11月26日" in Chinese.
    /// Anything that is not such a timestamp is shown as it is.
    pub fn date(&self, timestamp: &str) -> String {
        let day = timestamp.get(..10).unwrap_or(timestamp);
        let mut parts = day.split('-');
        let parsed = match (parts.next(), parts.next(), parts.next()) {
            (Some(y), Some(m), Some(d)) if y.len() == 4 => {
                match (y.parse::<u32>(), m.parse::<u32>(), d.parse::<u32>()) {
                    (Ok(y), Ok(m), Ok(d)) if (1..=12).contains(&m) && (1..=31).contains(&d) => {
                        Some((y, m, d))
                    }
                    _ => None,
                }
            }
            _ => None,
        };
        match (self.locale, parsed) {
            (_, None) => timestamp.to_owned(),
            (Locale::English | Locale::PseudoRtl, Some(_)) => day.to_owned(),
            (Locale::SimplifiedChinese, Some((y, m, d))) => format!("{y}年{m}月{d}日"),
        }
    }

    /// A moment kept as ISO 8601 in UTC ("2026-11-26T10:05:00Z"), to the minute, as the locale
    /// writes it: "2026-11-26 10:05 UTC" in English, "2026年11月26日 10:05 UTC" in Chinese.
    /// Anything that is not such a timestamp is shown as it is.
    pub fn date_time(&self, timestamp: &str) -> String {
        let day = self.date(timestamp);
        let clock = timestamp
            .get(10..16)
            .and_then(|t| t.strip_prefix(['T', ' ']))
            .filter(|hm| {
                let b = hm.as_bytes();
                b.len() == 5 && b[2] == b':' && [0, 1, 3, 4].iter().all(|&i| b[i].is_ascii_digit())
            });
        match clock {
            Some(hm) if day != timestamp => format!("{day} {hm} UTC"),
            _ => timestamp.to_owned(),
        }
    }

    /// The other locales, for the switch: (tag, native name).
    pub fn others(&self) -> Vec<(&'static str, &'static str)> {
        Locale::ALL
            .into_iter()
            .filter(|l| *l != self.locale)
            .map(|l| (l.tag(), l.native_name()))
            .collect()
    }

    /// The annotation page script's messages as a JSON object, each with its variables left
    /// as `{name}` for the script to fill in: one catalogue for the page and its script.
    pub fn script_messages(&self) -> String {
        let messages: serde_json::Map<String, serde_json::Value> = SCRIPT_MESSAGES
            .iter()
            .map(|(key, vars)| {
                let placeholders: Vec<(&str, String)> =
                    vars.iter().map(|v| (*v, format!("{{{v}}}"))).collect();
                let borrowed: Vec<(&str, &str)> =
                    placeholders.iter().map(|(n, p)| (*n, p.as_str())).collect();
                let text = if vars.is_empty() {
                    self.t(key)
                } else {
                    self.t_args(key, &borrowed)
                };
                ((*key).to_owned(), serde_json::Value::String(text))
            })
            .collect();
        serde_json::Value::Object(messages).to_string()
    }
}

/// The catalogue message of a refusal: `refusal-` and its code with dashes. Written out, as
/// [`msg`] keys, so that the catalogue check sees every one.
pub fn refusal_key(refusal: &Refusal) -> &'static str {
    match refusal {
        Refusal::NoDataset { .. } => msg("refusal-no-dataset"),
        Refusal::NoItem { .. } => msg("refusal-no-item"),
        Refusal::NoAnnotator { .. } => msg("refusal-no-annotator"),
        Refusal::NoEpisode { .. } => msg("refusal-no-episode"),
        Refusal::NoSubmission { .. } => msg("refusal-no-submission"),
        Refusal::NoRun { .. } => msg("refusal-no-run"),
        Refusal::NoFrame { .. } => msg("refusal-no-frame"),
        Refusal::NoAnswerYet { .. } => msg("refusal-no-answer-yet"),
        Refusal::NoStudy { .. } => msg("refusal-no-study"),
        Refusal::NoToken { .. } => msg("refusal-no-token"),
        Refusal::NoJob { .. } => msg("refusal-no-job"),
        Refusal::NoReported { .. } => msg("refusal-no-reported"),
        Refusal::NoCuratorGraphs { .. } => msg("refusal-no-curator-graphs"),
        Refusal::AnswersHidden { .. } => msg("refusal-answers-hidden"),
        Refusal::InviteLinkUsed => msg("refusal-invite-link-used"),
        Refusal::NoModelSubmission { .. } => msg("refusal-no-model-submission"),
        Refusal::NoPublishedSubmission { .. } => msg("refusal-no-published-submission"),
        Refusal::NoPublishedModel { .. } => msg("refusal-no-published-model"),
        Refusal::NoPaperFile { .. } => msg("refusal-no-paper-file"),
        Refusal::NoApiRoute { .. } => msg("refusal-no-api-route"),
        Refusal::NotLoggedIn => msg("refusal-not-logged-in"),
        Refusal::AdminOnly { .. } => msg("refusal-admin-only"),
        Refusal::StaleForm => msg("refusal-stale-form"),
        Refusal::NotAssigned { .. } => msg("refusal-not-assigned"),
        Refusal::ItemFinished { .. } => msg("refusal-item-finished"),
        Refusal::QueuePaused { .. } => msg("refusal-queue-paused"),
        Refusal::SlotsEmpty { .. } => msg("refusal-slots-empty"),
        Refusal::DraftInvalid { problem, .. } => match problem {
            DraftProblem::SlotCount { .. } => msg("refusal-draft-slot-count"),
            DraftProblem::LabelOutOfRange { .. } => msg("refusal-draft-label-out-of-range"),
            DraftProblem::PlacedTwice { .. } => msg("refusal-draft-placed-twice"),
            DraftProblem::HistoryTooLong { .. } => msg("refusal-draft-history-too-long"),
        },
        Refusal::ReasonMissing { .. } => msg("refusal-reason-missing"),
        Refusal::ReasonTooLong { .. } => msg("refusal-reason-too-long"),
        Refusal::PasswordsDiffer => msg("refusal-passwords-differ"),
        Refusal::LoginLinkUsed => msg("refusal-login-link-used"),
        Refusal::PasswordTooShort { .. } => msg("refusal-password-too-short"),
        Refusal::EpisodeHasNoGraphs { .. } => msg("refusal-episode-has-no-graphs"),
        Refusal::RunPrice { .. } => msg("refusal-run-price"),
        Refusal::ImportFolderUnset => msg("refusal-import-folder-unset"),
        Refusal::StudyExists { .. } => msg("refusal-study-exists"),
        Refusal::StudyBaselineMissing { .. } => msg("refusal-study-baseline-missing"),
        Refusal::StudyVariantMissing { .. } => msg("refusal-study-variant-missing"),
        Refusal::StudyVariantUnaligned { .. } => msg("refusal-study-variant-unaligned"),
        Refusal::ChallengeNotSplit { .. } => msg("refusal-challenge-not-split"),
        Refusal::ChallengeRevealed { .. } => msg("refusal-challenge-revealed"),
        Refusal::ChallengeAnswersPublic { .. } => msg("refusal-challenge-answers-public"),
        Refusal::ChallengeTooFewItems { .. } => msg("refusal-challenge-too-few-items"),
        Refusal::ChallengeAlreadySplit { .. } => msg("refusal-challenge-already-split"),
        Refusal::SelectionNotPublished { .. } => msg("refusal-selection-not-published"),
        Refusal::SelectionLimitReached { .. } => msg("refusal-selection-limit-reached"),
        Refusal::PrivatePartHidden { .. } => msg("refusal-private-part-hidden"),
        Refusal::EpisodeExists { .. } => msg("refusal-episode-exists"),
        Refusal::EpisodeImporting { .. } => msg("refusal-episode-importing"),
        Refusal::EpisodeTakenOver { .. } => msg("refusal-episode-taken-over"),
        Refusal::EpisodeNotResolved { .. } => msg("refusal-episode-not-resolved"),
        Refusal::TooFewKeyFrames { .. } => msg("refusal-too-few-key-frames"),
        Refusal::TooFewCurators { .. } => msg("refusal-too-few-curators"),
        Refusal::NoKeyFrame { .. } => msg("refusal-no-key-frame"),
        Refusal::FrameNameUnusable { .. } => msg("refusal-frame-name-unusable"),
        Refusal::DailyQuotaUsed { .. } => msg("refusal-daily-quota-used"),
        Refusal::TotalQuotaUsed { .. } => msg("refusal-total-quota-used"),
        Refusal::IdempotencyKeyReused { .. } => msg("refusal-idempotency-key-reused"),
        Refusal::EmptyList { .. } => msg("refusal-empty-list"),
        Refusal::ListedTwice { .. } => msg("refusal-listed-twice"),
        Refusal::LeavesNoItems { .. } => msg("refusal-leaves-no-items"),
        Refusal::TooFewForGold { .. } => msg("refusal-too-few-for-gold"),
        Refusal::GoldAndAttention { .. } => msg("refusal-gold-and-attention"),
        Refusal::AllChosenPaused => msg("refusal-all-chosen-paused"),
        Refusal::RecipientPaused { .. } => msg("refusal-recipient-paused"),
        Refusal::HandoverToSelf { .. } => msg("refusal-handover-to-self"),
        Refusal::NoRecipient { .. } => msg("refusal-no-recipient"),
        Refusal::DatasetExists { .. } => msg("refusal-dataset-exists"),
        Refusal::TokenMissing => msg("refusal-token-missing"),
        Refusal::AuthorizationMalformed => msg("refusal-authorization-malformed"),
        Refusal::TokenUnknown => msg("refusal-token-unknown"),
        Refusal::ScopeMissing { .. } => msg("refusal-scope-missing"),
        Refusal::NotModelOwner { .. } => msg("refusal-not-model-owner"),
        Refusal::FieldsRequired { .. } => msg("refusal-fields-required"),
        Refusal::ExactlyOneOf { .. } => msg("refusal-exactly-one-of"),
        Refusal::BothOrNeither { .. } => msg("refusal-both-or-neither"),
        Refusal::NotWith { .. } => msg("refusal-not-with"),
        Refusal::BadValue { expected, .. } => match expected {
            Expected::WholeNumber { .. } => msg("refusal-bad-value-whole-number"),
            Expected::WholeNumberFrom { .. } => msg("refusal-bad-value-whole-number-from"),
            Expected::Number => msg("refusal-bad-value-number"),
            Expected::NumberBetween { .. } => msg("refusal-bad-value-number-between"),
            Expected::Fraction => msg("refusal-bad-value-fraction"),
            Expected::OneOf(_) => msg("refusal-bad-value-one-of"),
            Expected::PlainName { .. } => msg("refusal-bad-value-plain-name"),
            Expected::SubmissionId => msg("refusal-bad-value-submission-id"),
            Expected::ReportedId => msg("refusal-bad-value-reported-id"),
        },
        Refusal::ImportPath { problem, .. } => match problem {
            ImportPathProblem::NotRelative => msg("refusal-import-path-not-relative"),
            ImportPathProblem::Missing => msg("refusal-import-path-missing"),
            ImportPathProblem::LeavesFolder => msg("refusal-import-path-leaves-folder"),
            ImportPathProblem::NotARelease => msg("refusal-import-path-not-a-release"),
            ImportPathProblem::ReleaseLeavesFolder => msg("refusal-import-release-leaves-folder"),
        },
    }
}

/// The messages `static/annotate.js` shows (live-region announcements, status text, labels),
/// with the variables each takes. The script reads them from the page, never its own copy.
pub const SCRIPT_MESSAGES: &[(&str, &[&str])] = &[
    (msg("js-slot-empty"), &["slot"]),
    (msg("js-slot-filled"), &["slot", "name"]),
    (msg("js-card-in-slot"), &["slot"]),
    (msg("js-saving"), &[]),
    (msg("js-saved"), &[]),
    (msg("js-not-saved"), &["error"]),
    (msg("js-placed"), &["name", "slot"]),
    (msg("js-swapped-moved"), &["name", "slot"]),
    (msg("js-swapped-returned"), &["name"]),
    (msg("js-cleared"), &["slot", "name"]),
    (msg("js-nothing-to-undo"), &[]),
    (msg("js-undone"), &[]),
    (msg("js-card-selected"), &["name"]),
    (msg("js-no-such-slot"), &["key", "count"]),
    (msg("js-slot-selected"), &["name"]),
    (msg("js-submitted"), &[]),
    (msg("js-not-submitted"), &["error"]),
    (msg("js-before-start"), &["name"]),
    (msg("js-before-empty"), &["slot"]),
    (msg("js-before-slot"), &["slot", "name"]),
    (msg("js-focus-slot-empty"), &["slot"]),
    (msg("js-focus-slot"), &["slot", "name"]),
    (msg("js-transition-before"), &["index", "name"]),
    (msg("js-transition-after"), &["index", "name"]),
    (msg("js-not-placed"), &["name"]),
    // The refusals a draft or an answer can meet, shown by their API code (`refusal-` and the
    // code with dashes) with the reply's `details`.
    (msg("refusal-item-finished"), &["item"]),
    (msg("refusal-queue-paused"), &["since"]),
    (msg("refusal-slots-empty"), &["item", "slots"]),
    (
        msg("refusal-draft-slot-count"),
        &["item", "field", "given", "expected"],
    ),
    (
        msg("refusal-draft-label-out-of-range"),
        &["item", "field", "slot", "label", "labels"],
    ),
    (
        msg("refusal-draft-placed-twice"),
        &["item", "field", "slot", "label"],
    ),
    (
        msg("refusal-draft-history-too-long"),
        &["item", "entries", "most"],
    ),
    (msg("refusal-not-assigned"), &["dataset", "item"]),
    (msg("refusal-no-item"), &["dataset", "item"]),
    (msg("refusal-no-dataset"), &["dataset"]),
    (msg("refusal-not-logged-in"), &[]),
    (msg("refusal-stale-form"), &[]),
];

/// The request's locale, for handlers that render pages.
impl FromRequestParts<AppState> for Tr {
    type Rejection = std::convert::Infallible;
    async fn from_request_parts(
        parts: &mut Parts,
        _state: &AppState,
    ) -> Result<Self, Self::Rejection> {
        Ok(Tr::of_request(&parts.headers, &parts.uri))
    }
}

/// A `Set-Cookie` value keeping the chosen locale for a year.
pub fn locale_cookie(locale: Locale) -> HeaderValue {
    let cookie = format!(
        "{LOCALE_COOKIE}={}; Path=/; SameSite=Lax; Max-Age={}",
        locale.tag(),
        Duration::from_secs(365 * 24 * 3600).as_secs()
    );
    // Tags are constants of the form [a-zA-Z-]+: always a valid header value.
    HeaderValue::from_str(&cookie).unwrap_or_else(|_| HeaderValue::from_static(""))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn accept_language_picks_the_highest_q_we_serve() {
        assert_eq!(
            Locale::negotiate("zh-CN,zh;q=0.9,en;q=0.8"),
            Some(Locale::SimplifiedChinese)
        );
        assert_eq!(
            Locale::negotiate("fr;q=1, en;q=0.5, zh;q=0.7"),
            Some(Locale::SimplifiedChinese)
        );
        assert_eq!(Locale::negotiate("en-GB, zh;q=0.2"), Some(Locale::English));
        assert_eq!(Locale::negotiate("zh-TW, zh-Hant;q=0.9"), None);
        assert_eq!(
            Locale::negotiate("zh-Hans-CN"),
            Some(Locale::SimplifiedChinese)
        );
        assert_eq!(Locale::negotiate("de, fr"), None);
        assert_eq!(Locale::negotiate("zh;q=0, en;q=0.1"), Some(Locale::English));
        assert_eq!(
            Locale::negotiate("zh;q=abc, en;q=0.1"),
            Some(Locale::English)
        );
        assert_eq!(Locale::negotiate(""), None);
    }

    #[test]
    fn cookie_wins_over_accept_language() {
        let mut headers = HeaderMap::new();
        headers.insert(header::ACCEPT_LANGUAGE, HeaderValue::from_static("zh-CN"));
        assert_eq!(Locale::of_request(&headers), Locale::SimplifiedChinese);
        headers.insert(header::COOKIE, HeaderValue::from_static("enact_lang=en"));
        assert_eq!(Locale::of_request(&headers), Locale::English);
        headers.insert(header::COOKIE, HeaderValue::from_static("enact_lang=xx"));
        assert_eq!(Locale::of_request(&headers), Locale::SimplifiedChinese);
        assert_eq!(Locale::of_request(&HeaderMap::new()), Locale::English);
    }

    #[test]
    fn the_pseudo_locale_is_chosen_only_by_its_cookie() {
        assert_eq!(Locale::from_tag("ar-XB"), None);
        assert_eq!(Locale::negotiate("ar-XB, ar"), None);
        let mut headers = HeaderMap::new();
        headers.insert(header::COOKIE, HeaderValue::from_static("enact_lang=ar-XB"));
        assert_eq!(Locale::of_request(&headers), Locale::PseudoRtl);
        let tr = Tr::of_request(&headers, &axum::http::Uri::from_static("/"));
        assert_eq!((tr.lang(), tr.dir()), ("ar-XB", "rtl"));
        assert_eq!(Tr::new(Locale::English).dir(), "ltr");
        // Every real locale is offered by the switch of a pseudo page; the pseudo one is not.
        assert_eq!(tr.others().len(), Locale::ALL.len());
    }

    #[test]
    fn pseudo_messages_are_wrapped_and_forty_percent_longer() {
        let tr = Tr::new(Locale::PseudoRtl);
        let english =
            Tr::new(Locale::English).t_nn("home-items-from-tasks", "items", 12, "tasks", 3);
        let text = tr.t_nn("home-items-from-tasks", "items", 12, "tasks", 3);
        assert!(
            text.starts_with("⟦12 items from 3 tasks") && text.ends_with('⟧'),
            "{text}"
        );
        let inner = text.chars().count() - 2;
        assert!(inner * 5 >= english.chars().count() * 7, "{text}");
        assert!(inner * 5 < english.chars().count() * 7 + 5 * 8, "{text}");
        assert_eq!(pseudo(""), "⟦⟧");
        let script: serde_json::Value =
            serde_json::from_str(&tr.script_messages()).expect("script messages are JSON");
        let slot = script["js-slot-empty"].as_str().expect("a message");
        assert!(slot.starts_with("⟦Slot {slot}: empty"), "{slot}");
    }

    #[test]
    fn decimals_are_grouped_and_rounded() {
        assert_eq!(decimal(8972.0, 0), "8,972");
        assert_eq!(decimal(1_234_567.25, 1), "1,234,567.2");
        assert_eq!(decimal(12.345, 1), "12.3");
        assert_eq!(decimal(999.96, 1), "1,000.0");
        assert_eq!(decimal(-0.04, 1), "0.0");
        assert_eq!(decimal(-1234.5, 1), "-1,234.5");
        assert_eq!(decimal(0.0, 0), "0");
        assert_eq!(decimal(f64::NAN, 1), "–");
        let zh = Tr::new(Locale::SimplifiedChinese);
        assert_eq!(zh.percent(0.125), "12.5%");
        assert_eq!(zh.percent_figure(Some(1.0)), "100.0");
        assert_eq!(zh.percent_figure(None), "–");
    }

    #[test]
    fn dates_follow_the_locale() {
        let en = Tr::new(Locale::English);
        let zh = Tr::new(Locale::SimplifiedChinese);
        assert_eq!(en.date("2026-11-06T10:00:00Z"), "2026-11-06");
        assert_eq!(zh.date("2026-11-06T10:00:00Z"), "2026年11月6日");
        assert_eq!(zh.date("2026-13-06"), "2026-13-06");
        assert_eq!(zh.date("yesterday"), "yesterday");
        assert_eq!(en.date_time("2026-11-06T10:05:00Z"), "2026-11-06 10:05 UTC");
        assert_eq!(
            zh.date_time("2026-11-06T10:05:00Z"),
            "2026年11月6日 10:05 UTC"
        );
        assert_eq!(zh.date_time("2026-11-06"), "2026-11-06");
        assert_eq!(zh.date_time("2026-11-06T1x:05:00Z"), "2026-11-06T1x:05:00Z");
    }

    /// A paused queue's refusal names when it was paused as the page's language writes a
    /// moment, not as the database keeps it.
    #[test]
    fn a_refusal_writes_its_moment_in_the_pages_language() {
        let paused = Refusal::QueuePaused {
            since: "2026-11-29T12:00:00Z".to_owned(),
        };
        let zh = Tr::new(Locale::SimplifiedChinese).refusal(&paused);
        assert!(zh.contains("自 2026年11月29日 12:00 UTC 起"), "{zh}");
        let en = Tr::new(Locale::English).refusal(&paused);
        assert!(en.contains("(since 2026-11-29 12:00 UTC)"), "{en}");
    }

    #[test]
    fn numbers_in_messages_are_grouped() {
        let zh = Tr::new(Locale::SimplifiedChinese);
        assert_eq!(
            zh.t_nn("home-items-from-tasks", "items", 8972, "tasks", 29),
            "8,972 个条目，来自 29 个任务"
        );
        let en = Tr::new(Locale::English);
        assert_eq!(
            en.t_nnn("dataset-shown", "first", 1001, "last", 1050, "total", 12000),
            "Items 1,001–1,050 of 12,000"
        );
    }

    #[test]
    fn messages_take_variables_and_plurals() {
        let en = Tr::new(Locale::English);
        assert_eq!(
            en.t_nn("home-items-from-tasks", "items", 1, "tasks", 1),
            "1 item from 1 task"
        );
        assert_eq!(
            en.t_nn("home-items-from-tasks", "items", 12, "tasks", 3),
            "12 items from 3 tasks"
        );
        let zh = Tr::new(Locale::SimplifiedChinese);
        assert_eq!(
            zh.t_nn("queue-finished", "done", 2, "total", 5),
            "已完成 2 / 5 个条目。"
        );
        assert_eq!(en.t("no-such-key"), "no-such-key");
        let script: serde_json::Value =
            serde_json::from_str(&zh.script_messages()).expect("script messages are JSON");
        assert_eq!(script["js-slot-empty"], "槽位 {slot}：空");
    }
}
