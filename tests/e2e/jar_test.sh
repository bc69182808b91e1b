#!/usr/bin/env bash
# The Java jar (for lcm-spy and Java subscribers) holds a class for every message type, and lcm-spy's
# type scanner, run on the jar, finds them all with their fingerprints.
set -euo pipefail
JAR="$1"
LCM_DIR="$2"
[[ -f "$JAR" ]] || { echo "jar_test: $JAR missing"; exit 1; }
listing=$(unzip -l "$JAR" 2>/dev/null || jar tf "$JAR")
for f in "$LCM_DIR"/*.lcm; do
  t=$(basename "$f" .lcm)
  grep -q "mcmt/$t.class" <<<"$listing" || { echo "jar_test: mcmt/$t.class missing from $JAR"; exit 1; }
done
# Each class exposes the LCM fingerprint lcm-spy uses to recognise messages.
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
cat >"$tmp/Check.java" <<'JAVA'
public class Check {
  public static void main(String[] args) throws Exception {
    for (String name : args) {
      Class<?> c = Class.forName("mcmt." + name);
      long hash = c.getField("LCM_FINGERPRINT").getLong(null);
      if (hash == 0) throw new RuntimeException(name + ": zero fingerprint");
      System.out.println(name + " " + Long.toHexString(hash));
    }
  }
}
JAVA
javac -d "$tmp" "$tmp/Check.java"
types=$(for f in "$LCM_DIR"/*.lcm; do basename "$f" .lcm; done)
java -cp "$tmp:$JAR:/usr/share/java/lcm.jar" Check $types
echo "jar_test: PASS"
