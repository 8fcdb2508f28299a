#!/usr/bin/env bash
# Screenshots of the episode editor for the README (docs/episode-editor-*.png): the browser
# test of the episode pages (tests/service/episode_browser.rs) takes them as it draws the
# graphs, when ENACT_HUB_SCREENSHOTS names a folder. Needs chromium and
# tests/browser/node_modules (scripts/test.sh installs both).
#
#   scripts/screenshots-episode.sh
set -euo pipefail
cd "$(dirname "$0")/.."
ENACT_HUB_SCREENSHOTS="$PWD/docs" cargo test --locked --test service \
  a_curator_draws_an_episode_in_chromium_and_its_items_verify -- --exact --nocapture
ls -l docs/episode-editor-*.png
