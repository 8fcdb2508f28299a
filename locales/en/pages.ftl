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
