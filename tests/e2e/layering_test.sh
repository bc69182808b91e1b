#!/usr/bin/env bash
# Layering (docs/architecture.md): core includes nothing of ours but the message types (mcmt/); every
# product component (detector, mapper, tracker, logger, viz, import) includes only core/, mcmt/ and its own
# folder. The tools (sim/, report/) may use any component; nothing of the product includes sim/.
#   layering_test.sh SOURCE_DIR
set -uo pipefail
SRC="$1"
bad=0
for comp in core detector mapper tracker logger viz import; do
  [[ -d "$SRC/$comp" ]] || continue
  while IFS= read -r hit; do
    file="${hit%%:*}"
    inc=$(sed -E 's/.*#include "([^"]+)".*/\1/' <<<"$hit")
    case "$inc" in
      mcmt/*|core/*|"$comp"/*) ;;
      */*) echo "layering_test: $file includes \"$inc\" (a $comp file may include core/, mcmt/ and $comp/ only)"; bad=1 ;;
    esac
  done < <(grep -rHn '#include "' "$SRC/$comp" --include=*.cc --include=*.h --include=*.hpp)
done
((bad == 0)) && echo "layering_test: PASS" || exit 1
