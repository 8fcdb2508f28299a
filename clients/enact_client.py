#!/usr/bin/env python3
"""Example enact-hub client: ask a model every item of a dataset (or of every dataset of an
ablation study), then submit its answers.

It is written over the `enact_hub` Python package (`pip install enact-hub`, or from a checkout
`PYTHONPATH=python`), whose `Hub` does the hub's side. For each item of DATASET on the hub,
this script

1. reads the item and its PNG frames through `Hub.items` (the hub's JSON API);
2. sends the images and the question to an OpenAI-compatible chat-completions endpoint
   (`POST {model_url}/chat/completions`) as one user message: for each image a text part with
   its label ("Current State", "Next State 1", ...) followed by the image as a base64
   `data:image/png` URL, then the question text;
3. keeps the model's raw answer text (the hub parses it, as ENACT's evaluation does);

then submits all answers with `Hub.submit` (compact JSONL to
`POST /api/v1/datasets/{dataset}/submissions?model=...` with the hub token), and prints the
scores the hub returns. Items not answered (with --limit, or when the model endpoint keeps
failing) count as unanswered: the hub scores every item of the dataset.

Needs Python 3.9+ and the `enact_hub` package (which brings `requests`). The binary's own
`enact-hub run DATASET --hub URL ...` does the same job resumably, with rate limits and cost;
this script shows the package's API. Example:

    export ENACT_HUB_TOKEN=ehub_...          # from your hub admin
    export OPENAI_API_KEY=sk-...             # if the model endpoint needs one
    python3 clients/enact_client.py --hub http://127.0.0.1:8080 --dataset enact \\
        --model-url https://api.openai.com/v1 --model gpt-4o --limit 5

With `--study NAME` instead of `--dataset`, the client reads the study
(`Hub.study`), runs the model over its baseline and then every variant dataset in turn, submits
each under the same model name, and prints the study report (`Hub.study_report`): Δ and p per
variant and direction.
`--answers-out` is then a folder, with one `{dataset}.jsonl` per dataset.

Exit status: 0 when the submission was stored, 1 on any error (the message says which
request failed and why).
"""

import argparse
import base64
import json
import os
import sys
import time

import requests

try:
    import enact_hub
except ImportError:
    sys.exit("error: this example needs the enact_hub package: pip install enact-hub (from a checkout: PYTHONPATH=python)")

USER_AGENT = "enact-hub-example-client/2 enact-hub/" + enact_hub.__version__


class ClientError(Exception):
    """A failure the user should read: which request, and what came back."""


def describe_failure(response):
    """The hub's JSON error message when there is one, else the start of the body."""
    try:
        body = response.json()
        if isinstance(body, dict) and "error" in body:
            text = str(body["error"])
            problems = body.get("problems") or []
            for p in problems[:10]:
                text += "\n  line {}: {}".format(p.get("line"), p.get("message"))
            return text
    except ValueError:
        pass
    return response.text[:500]


# The package's backoff: Retry-After when given, else exponential with jitter.
retry_delay = enact_hub.client.retry_delay


def request_with_retries(session, method, url, what, max_retries, base_delay, **kwargs):
    """Sends a request, retrying connection errors, 429 and 5xx with backoff."""
    for attempt in range(max_retries + 1):
        response = None
        try:
            response = session.request(method, url, **kwargs)
        except requests.RequestException as error:
            failure = "{} failed: {}".format(what, error)
        else:
            if response.status_code < 400:
                return response
            failure = "{}: HTTP {}: {}".format(what, response.status_code, describe_failure(response))
            if response.status_code != 429 and response.status_code < 500:
                raise ClientError(failure)
        if attempt == max_retries:
            raise ClientError("{} (gave up after {} attempts)".format(failure, attempt + 1))
        delay = retry_delay(response, attempt, base_delay)
        print("{}; retrying in {:.1f} s".format(failure, delay), file=sys.stderr)
        time.sleep(delay)
    raise ClientError(what + ": no attempt was made")


class ChatModel:
    """Any OpenAI-compatible chat-completions endpoint."""

    def __init__(self, base_url, model, api_key, timeout, max_retries, base_delay, max_tokens):
        self.url = base_url.rstrip("/") + "/chat/completions"
        self.model = model
        self.timeout = timeout
        self.max_retries = max_retries
        self.base_delay = base_delay
        self.max_tokens = max_tokens
        self.session = requests.Session()
        self.session.headers["User-Agent"] = USER_AGENT
        if api_key:
            self.session.headers["Authorization"] = "Bearer " + api_key

    def answer(self, item, image_urls):
        content = []
        for image, data_url in zip(item.images, image_urls):
            content.append({"type": "text", "text": image.label + ":"})
            content.append({"type": "image_url", "image_url": {"url": data_url}})
        content.append({"type": "text", "text": item.question})
        payload = {
            "model": self.model,
            "messages": [{"role": "user", "content": content}],
            "temperature": 0,
        }
        if self.max_tokens:
            payload["max_tokens"] = self.max_tokens
        response = request_with_retries(
            self.session,
            "POST",
            self.url,
            "model endpoint, item {}".format(item.id),
            self.max_retries,
            self.base_delay,
            json=payload,
            timeout=self.timeout,
        )
        try:
            message = response.json()["choices"][0]["message"]["content"]
        except (ValueError, KeyError, IndexError, TypeError):
            raise ClientError(
                "model endpoint, item {}: the reply has no choices[0].message.content: {}".format(
                    item.id, response.text[:300]
                )
            )
        if isinstance(message, list):
            # Some servers answer with content parts; keep their text.
            message = "".join(part.get("text", "") for part in message if isinstance(part, dict))
        return message if isinstance(message, str) else ""


def parse_args(argv):
    parser = argparse.ArgumentParser(
        description="Answer an enact-hub dataset with an OpenAI-compatible model and submit the answers."
    )
    parser.add_argument("--hub", default="http://127.0.0.1:8080", help="enact-hub base URL (default: %(default)s)")
    target = parser.add_mutually_exclusive_group(required=True)
    target.add_argument("--dataset", help="dataset name on the hub")
    target.add_argument("--study", help="an ablation study on the hub: answer its baseline and every variant dataset")
    parser.add_argument("--model-url", required=True, help="base URL of the chat-completions API, e.g. https://api.openai.com/v1")
    parser.add_argument("--model", required=True, help="model name sent to the endpoint")
    parser.add_argument("--api-key-env", default="OPENAI_API_KEY", help="environment variable holding the endpoint's API key, if any (default: %(default)s)")
    parser.add_argument("--hub-token-env", default="ENACT_HUB_TOKEN", help="environment variable holding the hub token (default: %(default)s)")
    parser.add_argument("--name", help="model name for the leaderboard (default: --model)")
    parser.add_argument("--description", default="", help="submission description")
    parser.add_argument("--prompt-version", default="enact_client.py/1", help="recorded with the submission (default: %(default)s)")
    parser.add_argument("--limit", type=int, help="answer only the first N items (the others count as unanswered)")
    parser.add_argument("--timeout", type=float, default=120.0, help="seconds per HTTP request (default: %(default)s)")
    parser.add_argument("--max-retries", type=int, default=5, help="retries on 429/5xx from the model endpoint (default: %(default)s)")
    parser.add_argument("--retry-delay", type=float, default=2.0, help="first backoff delay in seconds, doubled each retry (default: %(default)s)")
    parser.add_argument("--max-tokens", type=int, default=0, help="max_tokens for the model (0: not sent)")
    parser.add_argument("--answers-out", help="also write the answers JSONL to this file (with --study: to DIR/{dataset}.jsonl)")
    args = parser.parse_args(argv)
    if args.limit is not None and args.limit < 1:
        parser.error("--limit must be at least 1")
    return args


def main(argv=None):
    args = parse_args(argv)
    token = os.environ.get(args.hub_token_env, "").strip()
    if not token:
        print("error: set {} to your enact-hub token".format(args.hub_token_env), file=sys.stderr)
        return 1
    hub = enact_hub.Hub(args.hub, token, timeout=args.timeout)
    model = ChatModel(
        args.model_url,
        args.model,
        os.environ.get(args.api_key_env, "").strip(),
        args.timeout,
        args.max_retries,
        args.retry_delay,
        args.max_tokens,
    )
    try:
        if args.study:
            study = hub.study(args.study)
            datasets = [study["baseline"]] + [v["dataset"] for v in study["variants"]]
            print("study '{}': {} datasets".format(args.study, len(datasets)), file=sys.stderr)
        else:
            datasets = [args.dataset]
        submissions = []
        for dataset in datasets:
            answers_out = args.answers_out
            if args.study and answers_out:
                os.makedirs(answers_out, exist_ok=True)
                answers_out = os.path.join(answers_out, dataset + ".jsonl")
            submission = run_dataset(hub, model, args, dataset, answers_out)
            print_scores(submission)
            submissions.append(submission)
        report = hub.study_report(args.study, args.name or args.model) if args.study else None
    except (ClientError, enact_hub.HubError) as error:
        print("error: {}".format(error), file=sys.stderr)
        return 1
    if report is None:
        print(json.dumps(submissions[0], indent=2))
        return 0
    print(json.dumps({"submissions": submissions, "report": report}, indent=2))
    for cell in report["cells"]:
        print(
            "{}/{} {}: delta {} p {}".format(
                cell["family"], cell["variant"], cell["direction"], cell["delta"], cell["p"]
            ),
            file=sys.stderr,
        )
    return 0


def run_dataset(hub, model, args, dataset, answers_out):
    """Asks the model every item of `dataset` and submits the answers; the stored submission
    as the hub's JSON."""
    total = hub.dataset(dataset).items
    if args.limit is not None:
        total = min(args.limit, total)
    print("answering {} items of '{}' with {}".format(total, dataset, args.model), file=sys.stderr)
    answers = []
    for n, item in enumerate(hub.items(dataset, limit=args.limit), 1):
        images = ["data:image/png;base64," + base64.b64encode(image.data).decode("ascii") for image in item.images]
        answers.append((item.id, model.answer(item, images)))
        print("  {}/{} {}".format(n, total, item.id), file=sys.stderr)
    if answers_out:
        with open(answers_out, "w", encoding="utf-8") as out:
            for item_id, answer in answers:
                out.write(json.dumps({"id": item_id, "answer": answer}, ensure_ascii=False) + "\n")
    submission = hub.submit(
        dataset,
        args.name or args.model,
        answers,
        description=args.description,
        prompt_version=args.prompt_version,
        notes="sent by clients/enact_client.py; {} items answered".format(len(answers)),
    )
    return submission.raw


def print_scores(submission):
    scores = submission.get("scores") or {}
    overall = (scores.get("report") or {}).get("overall") or {}
    coverage = scores.get("coverage") or {}
    print(
        "submission {} on '{}': overall TA {} PA {}; coverage {}, parse failures {}".format(
            submission.get("id"),
            submission.get("dataset"),
            overall.get("task_accuracy"),
            overall.get("pairwise_accuracy"),
            coverage.get("coverage"),
            coverage.get("parse_failure_rate"),
        ),
        file=sys.stderr,
    )


if __name__ == "__main__":
    sys.exit(main())
