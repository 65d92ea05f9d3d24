#!/usr/bin/env bash
# Render an `incal report` HTML file in a real browser (headless Chromium).
#
#   scripts/render-report.sh REPORT.html [OUT.png]           screenshot, A4 width at 150 dpi (1240 x 1754 px)
#   scripts/render-report.sh --height PX REPORT.html [OUT.png] a taller screenshot (e.g. 12000: the whole report)
#   scripts/render-report.sh --pdf REPORT.html [OUT.pdf]     print to PDF with the print stylesheet (A4 certificate)
#   scripts/render-report.sh --pages REPORT.html [PREFIX]    print to PDF, then one PNG per page (PREFIX-1.png, ...)
#
# Needs Debian's `chromium` package (apt-get install -y chromium) and, for
# --pages, `pdftoppm` (apt-get install -y poppler-utils); installs nothing
# itself. The browser runs with a throw-away profile and no background
# networking, sync or component updates, so the picture shows what the
# self-contained file holds. Not part of CI.
set -euo pipefail

usage() {
    sed -n '2,14p' "$0" | sed 's/^# \{0,1\}//' >&2
    exit 2
}

mode=png
height=1754
while [[ $# -gt 0 ]]; do
    case $1 in
        --pdf) mode=pdf; shift ;;
        --pages) mode=pages; shift ;;
        --height)
            [[ $# -ge 2 && $2 =~ ^[0-9]+$ ]] || usage
            height=$2; shift 2 ;;
        -h|--help) usage ;;
        -*) usage ;;
        *) break ;;
    esac
done
[[ $# -ge 1 && $# -le 2 ]] || usage
in=$1
[[ -f "$in" ]] || { echo "render-report: $in: no such file" >&2; exit 2; }
base=${in%.html}
case $mode in
    png) out=${2:-$base.png} ;;
    pdf) out=${2:-$base.pdf} ;;
    pages) out=${2:-$base-page} ;;
esac

browser=""
for b in chromium chromium-browser; do
    if command -v "$b" >/dev/null 2>&1; then
        browser=$b
        break
    fi
done
if [[ -z "$browser" ]]; then
    echo "render-report: chromium is not installed; on Debian or Ubuntu: apt-get install -y chromium" >&2
    exit 1
fi
if [[ $mode == pages ]] && ! command -v pdftoppm >/dev/null 2>&1; then
    echo "render-report: pdftoppm is not installed; on Debian or Ubuntu: apt-get install -y poppler-utils" >&2
    exit 1
fi

abs() { echo "$(cd "$(dirname "$1")" && pwd)/$(basename "$1")"; }
abs_in=$(abs "$in")
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

flags=(
    --headless --no-sandbox --disable-gpu --disable-quic --no-first-run
    --disable-background-networking --disable-component-update --disable-sync
    --disable-extensions --hide-scrollbars --user-data-dir="$work/profile"
)
case $mode in
    png)
        abs_out=$(abs "$out")
        "$browser" "${flags[@]}" --window-size="1240,$height" --screenshot="$abs_out" "file://$abs_in" >/dev/null 2>&1
        [[ -s "$abs_out" ]] || { echo "render-report: $browser wrote no $out" >&2; exit 1; }
        echo "$out"
        ;;
    pdf)
        abs_out=$(abs "$out")
        "$browser" "${flags[@]}" --no-pdf-header-footer --print-to-pdf="$abs_out" "file://$abs_in" >/dev/null 2>&1
        [[ -s "$abs_out" ]] || { echo "render-report: $browser wrote no $out" >&2; exit 1; }
        echo "$out"
        ;;
    pages)
        "$browser" "${flags[@]}" --no-pdf-header-footer --print-to-pdf="$work/report.pdf" "file://$abs_in" >/dev/null 2>&1
        [[ -s "$work/report.pdf" ]] || { echo "render-report: $browser printed no PDF" >&2; exit 1; }
        pdftoppm -r 100 -png "$work/report.pdf" "$out"
        ls -1 "$out"-*.png
        ;;
esac
