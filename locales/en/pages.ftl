# enact-hub pages, English (the reference locale: every other locale has each of these keys).
# How to add a locale: README.md, "Languages of the pages".

## The frame of every page
nav-label = Site
nav-datasets = Datasets
nav-studies = Studies
nav-annotate = Annotate
footer = enact-hub · evaluation for the ENACT embodied world-modeling benchmark

## Error pages: the status, what it means, the use case's own message (in English)
error-detail = Details (as the hub reports them, in English):
error-back = Back to the datasets
error-reason-400 = Bad Request
error-explain-400 = The request was not understood: something in it is missing or malformed.
error-reason-401 = Unauthorized
error-explain-401 = You are not logged in, or your session has expired.
error-reason-403 = Forbidden
error-explain-403 = You are not allowed to do this.
error-reason-404 = Not Found
error-explain-404 = There is nothing here: the page, dataset or item does not exist.
error-reason-409 = Conflict
error-explain-409 = This conflicts with what is already stored.
error-reason-413 = Payload Too Large
error-explain-413 = What was sent is larger than this hub accepts.
error-reason-415 = Unsupported Media Type
error-explain-415 = What was sent is not in a format this hub reads.
error-reason-422 = Unprocessable Entity
error-explain-422 = What was sent was read, but some of it is not valid.
error-reason-429 = Too Many Requests
error-explain-429 = Too many attempts: please wait a little and try again.
error-reason-500 = Internal Server Error
error-explain-500 = Something went wrong on the hub's side. It has been logged.
error-reason-503 = Service Unavailable
error-explain-503 = The hub cannot do this right now: please try again later.

## Refusals: why a request was refused, one message per typed reason (src/app/refusal.rs).
## The API answers with the same reasons' codes; these are what the pages say.
refusal-no-dataset = no dataset named '{ $dataset }'
refusal-no-item = no item '{ $item }' in dataset '{ $dataset }'
refusal-no-annotator = no annotator named '{ $annotator }'
refusal-no-episode = no episode named '{ $episode }'
refusal-no-submission = no submission { $submission }
refusal-no-run = no model run { $run }
refusal-no-frame = no frame with hash '{ $frame }'
refusal-no-answer-yet = item '{ $item }' has no answer from you yet
refusal-not-logged-in = you are not logged in, or your session has expired: log in again
refusal-login-link-used = this login link is unknown or has already been used: a link logs in once; ask an admin for a new one, or log in with a password
refusal-admin-only = the admin pages are for admins; '{ $annotator }' is an annotator
refusal-stale-form = this page's form has expired: reload the page and try again
refusal-not-assigned = item '{ $item }' of dataset '{ $dataset }' is not assigned to you
refusal-item-finished = item '{ $item }' is already finished; its answer can no longer change
refusal-queue-paused = your queue is paused by an admin (since { $since }): you cannot open, save, answer or skip items until it is resumed; your drafts are kept
refusal-draft-slot-count = the draft of item '{ $item }' has { $given } slots in { $field }; the item has { $expected }
refusal-draft-label-out-of-range = the draft of item '{ $item }' puts card { $label } in slot { $slot } of { $field }; the item's cards are 1 to { $labels }
refusal-draft-placed-twice = the draft of item '{ $item }' places card { $label } twice ({ $field }, again in slot { $slot })
refusal-draft-history-too-long = the draft of item '{ $item }' keeps { $entries } undo steps; at most { $most } are kept
refusal-slots-empty = item '{ $item }': fill every slot before submitting (empty: { $slots })
refusal-reason-missing = { $action ->
        [flag] to flag item '{ $item }', say why in the reason field
       *[skip] to skip item '{ $item }', say why in the reason field
    }
refusal-reason-too-long = the reason is over { $limit } characters
refusal-passwords-differ = the two passwords differ
refusal-password-too-short = the password has { $chars } characters; use at least { $least }
refusal-episode-has-no-graphs = episode '{ $episode }' has no scene graphs yet: a curator must set them before it can be exported
refusal-run-price = { $field } must be a price of 0 or more (US dollars per million tokens), not { $price }
refusal-study-exists = a study named '{ $study }' exists already
refusal-study-baseline-missing = baseline: no dataset named '{ $dataset }'
refusal-study-variant-missing = variant { $variant }: no dataset named '{ $dataset }'
refusal-study-variant-unaligned = variant { $variant }: none of dataset '{ $dataset }''s { $items } items aligns with baseline '{ $baseline }''s { $baseline_items } (by id, or by task, type and key frames); a variant asks the baseline's questions with other images (made from the baseline's items)
refusal-import-folder-unset = this server imports releases from its own disk only when its operator names an import folder (ENACT_HUB_IMPORT_DIR); otherwise import on the server itself
refusal-import-path-not-relative = path: "{ $path }" must be a release's path relative to the server's import folder
refusal-import-path-missing = path: no "{ $path }" in the server's import folder
refusal-import-path-leaves-folder = path: "{ $path }" leaves the server's import folder
refusal-import-path-not-a-release = path: "{ $path }" is neither a release folder (with QA/enact_ordering.jsonl) nor a .jsonl file
refusal-import-release-leaves-folder = path: the release of "{ $path }" (its images' folder) leaves the server's import folder
refusal-challenge-not-split = dataset '{ $dataset }' is not split into a public and a private part: an admin splits it first, on the Challenges page
refusal-challenge-revealed = the private part of dataset '{ $dataset }' was revealed { $how ->
        [deadline] at its deadline
       *[hand] by hand
    } at { $at }: the final ranking, its settings and its selections are fixed
refusal-challenge-answers-public = dataset '{ $dataset }': its answers are public, so every submitter can score any part of it; only a dataset whose answers are hidden can be split (hide them first)
refusal-challenge-too-few-items = dataset '{ $dataset }' has { $items } items: a split needs two at least
refusal-challenge-already-split = dataset '{ $dataset }' was split at { $at } by { $by } (seed { $seed }, public share { $public_share }); a split is final
refusal-selection-not-published = submission { $submission } is { $visibility }: only a published submission can be selected for the final ranking
refusal-selection-limit-reached = the selection limit of dataset '{ $dataset }' is { $limit } submissions per account: account '{ $account }' has selected { $selected }; take one out first
refusal-private-part-hidden = the private part of dataset '{ $dataset }' is not revealed yet{ $scheduled ->
        [yes] {" "}(it will be at { $reveal_at })
       *[no] {""}
    }; until then its figures are for admins
refusal-bad-value-whole-number = { $field }: "{ $value }" is not a whole number from { $least } to { $most }
refusal-bad-value-whole-number-from = { $field }: "{ $value }" is not a whole number of { $least } or more
refusal-bad-value-number = { $field }: "{ $value }" is not a number
refusal-bad-value-number-between = { $field }: "{ $value }" is not a number from { $least } to { $most }
refusal-bad-value-fraction = { $field }: "{ $value }" is not a number above 0 and below 1
refusal-bad-value-one-of = { $field }: "{ $value }" is not one of: { $choices }
refusal-bad-value-submission-id = { $field }: "{ $value }" is not a submission's id
refusal-bad-value-reported-id = { $field }: "{ $value }" is not a reported result's id
refusal-no-study = no study named '{ $study }'
refusal-no-token = no live token with id or prefix "{ $token }"
refusal-no-job = job { $job } does not exist
refusal-no-reported = dataset '{ $dataset }' has no reported result { $reported }
refusal-no-curator-graphs = curator '{ $curator }' stored no graphs of episode '{ $episode }'
refusal-answers-hidden = the answers of dataset '{ $dataset }' are hidden, so what would show them is not shown
refusal-invite-link-used = this invite link is unknown or has already been used: ask an admin for a new one
refusal-no-model-submission = no submission of model '{ $model }' on dataset '{ $dataset }'
refusal-no-published-submission = { $field }: dataset '{ $dataset }' has no published submission { $submission }
refusal-no-published-model = { $field }: dataset '{ $dataset }' has no published row of model '{ $model }'{ $listed ->
        [yes] {" "}(its models: { $models })
       *[no] {""}
    }
refusal-no-paper-file = the paper folder of dataset '{ $dataset }' has no file '{ $file }' (it has { $files })
refusal-no-api-route = no API route { $path }: the routes are listed at /api/docs
refusal-fields-required = this request needs: { $fields }
refusal-exactly-one-of = give exactly one of: { $fields }
refusal-both-or-neither = give both of { $fields }, or neither
refusal-not-with = { $field } cannot be given with { $other }
refusal-token-missing = this request needs an API token
refusal-authorization-malformed = the Authorization header must read "Bearer TOKEN"
refusal-token-unknown = the API token is unknown or has been revoked
refusal-scope-missing = this token lacks the "{ $scope }" scope
refusal-not-model-owner = model '{ $model }' on dataset '{ $dataset }' was submitted by another account; only it or an admin may set its metadata
refusal-empty-list = { $field }: give one at least
refusal-listed-twice = { $field }: item '{ $item }' is listed twice
refusal-leaves-no-items = { $field }: the list names every item of dataset '{ $dataset }'; leave some for the Human row
refusal-too-few-for-gold = dataset '{ $dataset }' has { $items ->
        [one] { $items } item
       *[other] { $items } items
    }; gold items need at least two, so some are left for the Human row
refusal-gold-and-attention = { $field }: { $items } of dataset '{ $dataset }' { $field ->
        [checks] are gold items; they cannot be attention checks too
       *[items] are attention checks; they cannot be gold items too
    }
refusal-all-chosen-paused = every annotator chosen for the split has a paused queue: resume one or choose others
refusal-recipient-paused = annotator '{ $annotator }' has a paused queue; resume it or choose someone else
refusal-handover-to-self = '{ $annotator }' cannot hand items over to themselves
refusal-no-recipient = no other active annotator with a running queue to hand '{ $annotator }''s items to: create one, resume one, or name the recipients
refusal-dataset-exists = a dataset named '{ $dataset }' exists already
refusal-daily-quota-used = this token has used its { $limit } submissions for today (UTC); try again in { $retry_after } s
refusal-total-quota-used = this token's total quota is used up: { $used } of { $limit } submissions made; waiting will not help, ask an admin for a new token or a larger total quota
refusal-idempotency-key-reused = this Idempotency-Key was used for submission { $submission } with a different body
refusal-bad-value-plain-name = { $field }: "{ $value }" is not a name of 1 to { $most } letters, digits, '_' or '-'
refusal-episode-exists = an episode named '{ $episode }' exists already
refusal-episode-importing = episode '{ $episode }' is being imported since { $since } (by { $by }); if that import was stopped, its claim on the name lapses in { $lapses_in } s and the next import takes the name over
refusal-episode-taken-over = the import of episode '{ $episode }' wrote nothing for over { $after } s and another import of the name took it over; this one stopped
refusal-episode-not-resolved = episode '{ $episode }' has graphs from several curators ({ $curators }): choose the ones to export first, on the episode's page
refusal-too-few-key-frames = episode '{ $episode }' has { $key_frames } key frames; an export needs at least { $least } (ENACT's shortest step length, 3, orders 4 key frames)
refusal-too-few-curators = episode '{ $episode }' has graphs from { $curators ->
        [one] { $curators } curator
       *[other] { $curators } curators
    }: a comparison needs two
refusal-no-key-frame = curator '{ $curator }' marked no key frame at frame { $frame } of episode '{ $episode }'
refusal-frame-name-unusable = an uploaded frame has no usable file name ("{ $name }"): frames are ordered by name

## Logging in
login-title = Log in
login-heading = Log in to annotate
login-name = Name
login-password = Password
login-submit = Log in
login-no-account = No account yet? An admin creates one and sends you a single-use invite link.
login-error-expired = the login form expired or lacks its CSRF token: please try again
login-error-missing = give your name and your password
login-error-wrong = unknown name or wrong password
# The limiter's own message says whose logins are blocked and for how long.
login-error-limited = { $detail }

## The annotator's queue
queue-title = Your queue
queue-logged-in-as = Logged in as
queue-admin = Admin
queue-log-out = Log out
queue-finished = { $done } of { $total } items finished.
queue-resume = Resume where you left off
queue-continue = Continue
queue-all-done = Every item assigned to you is finished. Thank you!
queue-empty = No item is assigned to you yet.
queue-paused = Your queue is paused by an admin. You can see your items, but you cannot open, answer or skip them until it is resumed; your drafts are kept.
queue-progress-caption = Finished / assigned, by direction and step length (L = number of images)

## Table headings and the benchmark's words
col-direction = Direction
col-item = Item
col-dataset = Dataset
col-status = Status
direction-forward = forward
direction-inverse = inverse
status-todo = to do
status-started = in progress
status-answered = answered
status-skipped = skipped
status-flagged = flagged

## The annotation pages (forward and inverse)
annotate-title-forward = Forward item
annotate-title-inverse = Inverse item
annotate-task-forward = Forward world modeling: put the future images in the order the actions produce them
annotate-task-inverse = Inverse world modeling: give each state transition the action that caused it
annotate-instructions = Instructions (the question the models get)
annotate-untranslated = The question is shown exactly as the models get it, in English, and is never translated: it is part of the benchmark.
annotate-untranslated-actions = The action descriptions are part of the benchmark and are shown exactly as the dataset holds them, untranslated.
annotate-finished = You have finished this item.
annotate-attention-keep-forward = Attention check: whatever the actions say, put the candidate images in the slots in the order they are listed: Next State 1 in slot 1, Next State 2 in slot 2, and so on.
annotate-attention-reverse-forward = Attention check: whatever the actions say, put the frames in reverse order: the last listed candidate image in slot 1, the one before it in slot 2, and so on, Next State 1 in the last slot.
annotate-attention-keep-inverse = Attention check: whatever the images show, put the candidate actions in the slots in the order they are listed: Action 1 in slot 1, Action 2 in slot 2, and so on.
annotate-attention-reverse-inverse = Attention check: whatever the images show, put the actions in reverse order: the last listed candidate action in slot 1, the one before it in slot 2, and so on, Action 1 in the last slot.
annotate-next = Continue with the next one
annotate-answer = Answer
annotate-steps = Steps: action k leads to image k
annotate-transitions = State transitions, in order
annotate-enlarge = Enlarge { $name }
annotate-alt-current = Current state, where the actions start ({ $name })
annotate-current-caption = { $name }: where the actions start
annotate-alt-before = Transition { $index }, state before ({ $name })
annotate-alt-after = Transition { $index }, state after ({ $name })
annotate-alt-candidate = Candidate { $name }
annotate-undo = Undo
annotate-submit = Submit answer
annotate-candidate-images = Candidate images
annotate-candidate-actions = Candidate actions
annotate-shuffled = (shuffled)
annotate-keyboard-help = Drag a card onto a slot, or click a card and then a slot. Keyboard: arrow keys move between slots and cards (the inspector follows); on a card press the slot number; Backspace on a slot or a placed card clears it; a card put on a filled slot swaps; Ctrl+Z or the Undo button undoes.
annotate-inspector = Inspector: the image under focus, large
annotate-inspector-hint = Point at or focus an image to see it here, large.
annotate-skip-summary = Skip or flag this item
annotate-reason = Reason
annotate-skip = Skip
annotate-flag = Flag a problem
annotate-lightbox = Enlarged image
annotate-close = Close

## What the annotation page's script says (live region, status, labels)
js-slot-empty = Slot { $slot }: empty
js-slot-filled = Slot { $slot }: { $name }
js-card-in-slot = in slot { $slot }
js-saving = Saving…
js-saved = Saved
js-not-saved = Not saved: { $error }
js-placed = { $name } placed in slot { $slot }.
js-swapped-moved = { $name } moved to slot { $slot }.
js-swapped-returned = { $name } returned to the library.
js-cleared = Slot { $slot } cleared; { $name } returned to the library.
js-nothing-to-undo = Nothing to undo.
js-undone = Undone.
js-card-selected = { $name } selected: choose a slot.
js-no-such-slot = There is no slot { $key }; slots go from 1 to { $count }.
js-slot-selected = { $name } selected: choose another slot to move it.
js-submitted = Answer submitted.
js-not-submitted = Not submitted: { $error }
js-before-start = before: { $name }
js-before-empty = before: slot { $slot } is empty
js-before-slot = before: slot { $slot }, { $name }
js-focus-slot-empty = slot { $slot }: empty
js-focus-slot = slot { $slot }: { $name }
js-transition-before = transition { $index }, before: { $name }
js-transition-after = transition { $index }, after: { $name }
js-not-placed = { $name } (not placed)

## Home page: the datasets
home-submitting = Submitting a model? See the
home-api-docs = API documentation.
home-empty = There is no dataset in this database yet.
home-import = Import an ENACT release (a folder holding QA/enact_ordering.jsonl and its images):
home-demo = or start the service on the built-in demo dataset:
home-items-from-tasks = { $items ->
    [one] { $items } item
   *[other] { $items } items
  } from { $tasks ->
    [one] { $tasks } task
   *[other] { $tasks } tasks
  }
home-imported = imported { $date }
home-leaderboard = leaderboard
home-counts-caption = Items by direction and step length (L = number of images)
col-all = All
col-step-length = Step length
col-task = Task

## A dataset's items
dataset-download = Download every item as an ENACT release archive (tar)
dataset-download-what = — QA/enact_ordering.jsonl and the images. Answers are included only if the dataset's answers are public.
dataset-any = any
dataset-show = Show
dataset-no-match = No item matches these filters.
dataset-shown = Items { $first }–{ $last } of { $total }
pager-label = pages
pager-previous = Previous
pager-next = Next

## One item, read-only
item-crumb = item
item-counts = { $images } images, { $actions } actions
item-type = Type
item-images = Images
item-images-forward = (current state, then the future states as shuffled in the item)
item-images-inverse = (in chronological order)
item-alt-image = Image at position { $position } of the item ({ $name })
item-actions = Actions
item-actions-forward = (in order)
item-question = Full question text, as given to models

## The leaderboard
leaderboard-title = Leaderboard: { $dataset }
leaderboard-heading = Leaderboard:
leaderboard-policy = Strict policy: every item of the dataset counts; a missing or unreadable answer scores 0.
leaderboard-metrics = TA = task accuracy, PA = pairwise accuracy, in percent. The interval is a 95% percentile bootstrap over items (1,000 resamples).
leaderboard-metric-version = Metric version { $version }; a row computed with an older one is marked
leaderboard-older-metric = older metric
leaderboard-error-analysis = Error analysis
leaderboard-compare = Compare two rows
leaderboard-explore = Explore every answer
leaderboard-empty = No submission has been published for this dataset yet.
leaderboard-how-to-submit = Submit ENACT model-output JSONL with an API token:
leaderboard-ranked-by = Ranked by
leaderboard-ranking-help = (click a column's TA or PA to rank by it); equal values as shown share a rank.
leaderboard-every-listed = Every published submission is listed.
leaderboard-one-per-model = One row per model
leaderboard-latest-listed = One row per account and model: its latest published submission.
leaderboard-every-submission = Every submission
leaderboard-all-models = all models
leaderboard-only-model = Only model { $model }
leaderboard-only-account = Only account { $account }
leaderboard-only-model-of-account = Only model { $model } of account { $account }
leaderboard-caption = Overall, forward and inverse world modeling; per step length L (number of images)
leaderboard-draw = Draw in the chart
leaderboard-draw-model = draw { $model } in the chart
leaderboard-model = Model
leaderboard-overall = Overall
leaderboard-forward = Forward world modeling
leaderboard-inverse = Inverse world modeling
leaderboard-coverage = Coverage
leaderboard-parse-failures = Parse failures
leaderboard-submitted = Submitted
leaderboard-ta-ci = TA 95% CI
leaderboard-pa-ci = PA 95% CI
leaderboard-baseline = baseline
leaderboard-attempts = { $count ->
    [one] { $count } attempt
   *[other] { $count } attempts
  }
leaderboard-few-answers = only { $count ->
    [one] { $count } answer
   *[other] { $count } answers
  }: fewer than { $minimum }
leaderboard-outdated = computed with metric version { $version } (current: { $current }); not comparable with the other rows until an admin rescores it
leaderboard-human-items = { $items } of { $total } items
leaderboard-human-annotators = { $count ->
    [one] { $count } annotator
   *[other] { $count } annotators
  }
leaderboard-human-answers = { $count ->
    [one] { $count } answer
   *[other] { $count } answers
  }
leaderboard-human-gold = ; answers on { $count ->
    [one] the { $count } gold item
   *[other] the { $count } gold items
  } left out
leaderboard-human-excluded = ; { $count ->
    [one] { $count } annotator
   *[other] { $count } annotators
  } excluded by an admin
leaderboard-human-unranked = ; not ranked
intervals-note = Intervals: 95 % percentile bootstrap, resampling { $resampling }. Items of one activity (ENACT's task_name) share scenes and fail together, so by default whole activities are resampled.
leaderboard-resample-items = Resample items one by one instead
leaderboard-resample-activities = Resample whole activities (the default)
leaderboard-intervals-by-items = this row's intervals resample items: it was scored before the hub resampled activities
leaderboard-human-note = The Human row is a reference, never ranked among models; a figure marked † rests on fewer than five human answers. Answers on gold items (items with a known answer mixed into annotators' queues to check their work) never count in it, nor do the answers of annotators an admin excluded.
leaderboard-reported-count = { $count ->
    [one] This dataset has { $count } result a paper published (a reported row).
   *[other] This dataset has { $count } results papers published (reported rows).
}
leaderboard-reported-show = Show reported rows
leaderboard-reported-hide = Hide reported rows
leaderboard-reported-badge = reported
leaderboard-reported-source = source: { $source }
leaderboard-reported-unranked = not ranked: a reported row
leaderboard-reported-note = Reported rows are numbers a paper published, entered as data: not scored by this hub, with no interval and no per-item data, and never ranked against the hub's rows (their rank is left empty). The paper's appendix tables give step-length cells only, so their overall, forward and inverse totals are empty.
leaderboard-provenance-run = run
leaderboard-provenance-run-meaning = this hub asked the model itself and scored the replies it kept; the link shows the run's stamp
leaderboard-provenance-submitted = submitted
leaderboard-provenance-submitted-meaning = answers uploaded by the submitter; this hub scored them but did not see the model answer
leaderboard-provenance-filter = Only rows that are:
leaderboard-provenance-all = any provenance
leaderboard-model-link = about the model
leaderboard-challenge-public = Challenge under way: these figures are over the public part only, { $public } of the { $total } items. The private part ({ $private } of { $total }) is revealed at { $deadline } (UTC), and the final ranking is over it.
leaderboard-challenge-public-no-deadline = Challenge under way: these figures are over the public part only, { $public } of the { $total } items. The private part ({ $private } of { $total }) is revealed when an admin reveals it, and the final ranking is over it.
leaderboard-challenge-public-after = The public part's figures ({ $public } of the { $total } items), as the board stood during the challenge. The private part was revealed on { $revealed }.
leaderboard-challenge-private = Final ranking: the private part was revealed on { $revealed }. These figures are over its { $private } of the { $total } items, for the submissions each account selected (its latest, when it selected none); each row shows its rank over the public part and the change.
leaderboard-challenge-preview = Admin preview: the final ranking over the private part ({ $private } of the { $total } items), as a reveal now would make it. Submitters cannot see it before the reveal.
leaderboard-challenge-show-preview = Preview the final ranking
leaderboard-challenge-show-final = The final ranking
leaderboard-challenge-show-public = The public part's board
leaderboard-account-submissions = { $count ->
    [one] { $count } submission by this account
   *[other] { $count } submissions by this account
  }
leaderboard-standing = public rank { $public }, private rank { $private }: { $change }
leaderboard-rank-up = { $places ->
    [one] up { $places } place
   *[other] up { $places } places
  }
leaderboard-rank-down = { $places ->
    [one] down { $places } place
   *[other] down { $places } places
  }
leaderboard-rank-same = no change
leaderboard-page-of = page { $page } of { $pages }
leaderboard-ranked-rows = { $count ->
    [one] { $count } ranked row
   *[other] { $count } ranked rows
  }
leaderboard-chart-heading = Task accuracy against step length
leaderboard-chart-checked = The models checked in the table, with the Human row and baselines.
leaderboard-chart-best = The best ten by { $sort }, with the Human row and baselines.
leaderboard-chart-draw = Draw the checked models
leaderboard-chart-label = Task accuracy (%) against step length L, one line per model; forward and inverse panels
leaderboard-axis-step = Step length L
leaderboard-axis-ta = TA (%)
leaderboard-group-overall = overall
leaderboard-group-forward = forward
leaderboard-group-inverse = inverse
leaderboard-sort = { $group } { $metric }
leaderboard-sort-step = { $group } { $metric } at L={ $step }

## Error analysis
errors-heading = Error analysis: { $dataset }
errors-leaderboard = Leaderboard
errors-explanation = Each answer of the right length is compared step by step with the truth: true and predicted state changes are matched, and the rest classed as in the ENACT paper (polarity inversion, predicate substitution, entity substitution, omission, hallucination) and by what they are about. Hand figures count grasping changes of each gripper; mixing is the share of a hand's true changes given to the other hand.
errors-empty = No published submission and no human answer yet.
errors-examples-withheld = Examples are not shown: the answers of dataset “{ $dataset }” are hidden, so only aggregate figures are.
errors-row = row
errors-overall = overall
errors-structural = Structural errors
errors-semantic = Semantic errors
errors-hands = Hands
errors-structural-caption = Share of each row's errors by structural class
errors-semantic-caption = Share of each row's errors by semantic category
errors-hands-caption = Left- and right-hand precision, recall and mixing; whiskers are one standard error
errors-of = Errors of { $row }
errors-all-rows = All rows of { $dataset }
errors-row-structural-caption = Share of errors by structural class, forward and inverse
errors-row-semantic-caption = Share of errors by semantic category, forward and inverse
errors-row-hands-caption = Left- and right-hand precision, recall and mixing, forward and inverse; whiskers are one standard error
errors-examples = Examples
errors-none = No errors to show.
errors-class = class
errors-step = step
errors-true-change = true change
errors-predicted-change = predicted change
errors-analysed = analysed
errors-not-analysed = not analysed
errors-errors = errors
errors-structural-share = structural (share of errors)
errors-semantic-share = semantic (share of errors)
errors-hands-se = hands (± SE)
errors-accepted-incomplete = accepted but incomplete
errors-answers = answers
errors-steps = steps
errors-polarity-inversion = Polarity inversion
errors-predicate-substitution = Predicate substitution
errors-entity-substitution = Entity substitution
errors-omission = Omission
errors-hallucination = Hallucination
errors-spatial-relations = Spatial relations
errors-functional-states = Functional states
errors-material-states = Material states
errors-agent-interaction = Agent interaction
errors-hand-left = left
errors-hand-right = right
errors-precision = precision
errors-recall = recall
errors-mixing = mixing

## Ablation studies
studies-title = Ablation studies
studies-explanation = A study asks a baseline dataset's questions again with other images (image realism, camera, robot appearance) and reports, for a model or the Human row, how pairwise accuracy changes on each variant: Δ with the paper's Welch test, and paired tests on the same items.
studies-empty = No study yet. An admin creates one with enact-hub study create or at
studies-study = Study
studies-baseline = Baseline
studies-variants = Variants
studies-created = Created
studies-created-by = created { $date } by { $who }
study-title = Study: { $name }
study-items = { $count ->
    [one] { $count } item
   *[other] { $count } items
  }
study-all = all studies
study-variants-caption = Variants and how their items align with the baseline's
study-family = Family
study-variant = Variant
study-aligned = Aligned
study-by-id = by id
study-by-key-frames = by task, type and key frames
study-unaligned = unaligned (baseline / variant)
study-judged-differently = judged differently
study-not-computed = not computed
study-judged-warning = { $count } aligned items are judged by other rules than the baseline's (another ground truth or another signature table), so their scores differ for reasons other than the images. Import a variant with the baseline's scene graphs:
study-compare = Compare
study-choose = choose a model…
study-human = Human (annotators)
study-per-step = per step length
study-show = Show report
study-report-heading = { $row } on each variant against the baseline
study-delta-explained = Δ = mean pairwise accuracy on the variant − on the baseline, over the aligned items. Colour: the band of the two-tailed Welch p-value (the paper's test); darker red is more significant. Downloads:
study-all-files = all files (tar)
study-cells-caption = Welch (unpaired, as in the paper) and paired tests per variant and direction
study-n = n (baseline / variant)
study-signs = signs (↑ ↓ =)
study-handedness = Handedness (the paper's panel C.2)
study-handedness-explained = Left- and right-hand precision, recall and mixing (the share of one hand's true changes given to the other hand), ± standard error, on the baseline and each variant.

## Accepting an invite
invite-title = Set your password
invite-welcome = Welcome, { $name }
invite-choose = Choose a password (at least { $count } characters). This link works once.
invite-repeat = Repeat it
invite-submit = Set password and start
errors-figures-table = Error figures per row
errors-examples-of = Examples: { $category }

## The paper's tables (/datasets/{dataset}/paper)
paper-title = The paper's tables
paper-heading = The paper's tables: { $dataset }
paper-explanation = ENACT's result tables from this dataset: the results papers published (entered by an admin) beside this hub's own rows (each model's latest published submission, and the Human row from this hub's annotators). Best and second-best are marked within each category, as the paper marks them; the hub's rows form a category of their own unless their metadata names one.
paper-leaderboard = Leaderboard
paper-models = Rows
paper-models-hint = Model names, comma-separated, in the order to print them; empty for every row.
paper-metric = Metric
paper-metric-both = Both tables
paper-task-accuracy = Task accuracy
paper-pairwise-accuracy = Pairwise accuracy
paper-intervals = Show the hub rows' 95 % bootstrap intervals
paper-apply = Make the tables
paper-download = Download every table, figure and provenance.json (tar)
paper-marks = Marks:
paper-mark-first = best in its category
paper-mark-second = second-best in its category
paper-standalone = standalone .tex
paper-model = Model
paper-source = Source
paper-forward = Forward world modeling
paper-inverse = Inverse world modeling
paper-category-proprietary = Proprietary models
paper-category-open-weight = Open-weight models
paper-category-human = Human performance
paper-figure-alt = { $metric } by step length, forward and inverse, one line per row
paper-figure-caption = { $metric } by step length.
paper-error-analysis = Error analysis
paper-error-analysis-alt = Shares of structural error classes (polarity inversion, predicate substitution, entity substitution, omission, hallucination) per hub row, forward and inverse
paper-error-analysis-caption = Error distribution of the hub's chosen rows, by direction; published rows have no per-item answers to analyse.
paper-error-analysis-none = No hub row (submission or Human row) is chosen, so there is no error-analysis figure: published rows have no per-item answers to analyse.
paper-studies = Studies of this dataset
paper-study-alt = Heat map of study { $study } for { $row }: Δ mean pairwise accuracy of each variant against this dataset, forward and inverse, coloured by the band of the p-value
paper-study-caption = Study { $study }, reported for { $row }.
paper-study-link = The study
paper-reproduction = Reproduction check
paper-reproduction-none = No model that a paper published has also been scored on this hub for this dataset.
paper-reproduction-explanation = Each published model that this hub also scored (same name), cell by cell: the published value, the hub's, the difference in points, the hub's 95 % bootstrap interval, and whether the published value lies inside it.
paper-cell = Cell
paper-reported = Published
paper-hub = This hub
paper-difference = Difference
paper-interval = Hub interval
paper-inside = Published value inside?
paper-inside-yes = inside
paper-inside-no = outside

## Two leaderboard rows compared item by item (/datasets/{dataset}/compare)
compare-title = Compare two rows
compare-heading = Compare two rows: { $dataset }
compare-explanation = Two rows of the leaderboard, compared on the items both answered. Overlapping leaderboard intervals say little about which is better; a paired comparison asks on how many items one succeeds where the other fails. Each difference (A − B, in points) comes with a paired bootstrap interval, and task success with McNemar's exact test.
compare-leaderboard = Leaderboard
compare-row-a = Row A
compare-row-b = Row B
compare-rows-hint = A model name (its leaderboard row) or a submission number.
intervals-resample = Intervals resample
intervals-resampling-activities = whole activities with their items
intervals-resampling-items = items one by one
compare-apply = Compare
compare-no-rows = This leaderboard has no published submission yet.
compare-result = { $a } against { $b }
compare-method = Intervals: { $level } % paired percentile bootstrap, resampling { $resampling }.
compare-resamples = { $count ->
    [one] { $count } resample.
   *[other] { $count } resamples.
}
compare-metric-versions = The two rows were scored under different metric versions ({ $a } and { $b }): rescoring the older one makes them comparable.
compare-unpaired = { $count ->
    [one] { $count } item has a verdict in only one of the rows and is left out.
   *[other] { $count } items have a verdict in only one of the rows and are left out.
}
compare-table = Task and pairwise accuracy of both rows, their differences and McNemar's test
compare-cell = Items
compare-n = Count
compare-ta-a = TA A
compare-ta-b = TA B
compare-ta-difference = TA A − B [interval]
compare-a-only = Only A right
compare-b-only = Only B right
compare-mcnemar = McNemar p
compare-pa-a = PA A
compare-pa-b = PA B
compare-pa-difference = PA A − B [interval]
compare-significant = under 0.05
compare-reading = An interval that excludes 0 and a McNemar p under 0.05 (in bold) say the difference is unlikely to be chance. With items from few activities, resampling activities gives the honest, wider interval.
compare-overall = Every item
compare-forward = Forward
compare-inverse = Inverse
compare-only-a = Items only { $row } gets right
compare-only-b = Items only { $row } gets right
compare-none = None.
compare-items-hidden = This dataset's answers are hidden: per-item verdicts are shown to admins only.

## Every item against every row (/datasets/{dataset}/explore)
explore-title = Explore the answers
explore-heading = Every item, every row: { $dataset }
explore-explanation = Each item of the dataset against each row of the leaderboard and the Human column, with the verdict of each answer. The Human column takes the majority of the annotators' answers the Human row counts: right when more than half are right. A model row without an answer counts as wrong. Filter by kind of item and by pattern, and sort by difficulty (the share of rows wrong) or by one row; each option says how many items it would show.
explore-leaderboard = Leaderboard
explore-activity = Activity
explore-pattern = Pattern
explore-pattern-any = Every item
explore-pattern-humans-right = Humans right, every model wrong
explore-pattern-disagree = Models disagree
explore-pattern-unparseable = Unparseable by any model
explore-pattern-only = Only { $row } right
explore-sort = Order
explore-sort-difficulty = Hardest first
explore-sort-wrong = { $row }: wrong first
explore-sort-right = { $row }: right first
explore-option-count = { $label } ({ $count })
explore-apply = Show
explore-matching = Items matching: { $matching } of { $total }.
explore-permalink = Link to this view
explore-csv = CSV of every matching item
explore-legend = Verdicts:
explore-none = No item matches this view.
explore-table = Verdicts on the matching items, page { $page } of { $pages }
explore-kind = Kind
explore-wrong-rows = Rows wrong
explore-human = Human
explore-baseline = baseline
explore-right-count = { $count } right
explore-page = Page { $page } of { $pages }

## The item page's answers
item-answers = Answers
item-truth = The true order:
item-gold = gold item
item-answers-models = Leaderboard rows
item-answers-humans = Annotators
item-answers-no-models = No published submission has answered this item.
item-answers-no-humans = No annotator has answered this item yet.
item-answers-hidden = This dataset's answers are hidden: the answers to its items are shown to admins only.
item-answer-who = Who
item-answer-order = Answer
item-answer-verdict = Verdict
item-answer-pairwise = Pairwise accuracy
item-answer-why = Why
item-answer-baseline = baseline
item-answer-excluded = excluded from the Human row
item-verdict-exact = exact
item-verdict-equivalent = accepted as equivalent
item-verdict-wrong = wrong
item-verdict-unparseable = unparseable
item-verdict-missing = missing
item-why = Steps the verifier rejects
item-why-step = Step { $step } (label { $label })
item-why-implied = The answer implies, and the truth does not:
item-why-missed = The true step has, and the answer does not:
item-why-pairs = Pairs in the wrong order:
