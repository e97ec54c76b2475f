#!/usr/bin/env bash
# check_deb.sh SRC_DIR DEB_DIR VERSION "PROGRAMS": installs the package built by
# build_deb.sh into a scratch root (dpkg -x) and checks what lands where, the
# control data (Depends, conffiles, maintainer scripts), then verifies the
# installed units with systemd-analyze pointed at the scratch root's binaries.
# PEX_PKG_DROP=PATH removes PATH from the scratch root first (the self-test: the
# check must then fail naming it). Every failure is printed; exit 1 if any.
set -uo pipefail   # no -e: every check runs and reports
src=$1 debdir=$2 version=$3 programs=$4
deb=$(ls "$debdir"/polyexplore_*.deb) || exit 1
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
root=$tmp/root
fails=0 robot_values=0
fail() { echo "FAIL: $*"; fails=$((fails + 1)); }

arch=$(dpkg --print-architecture)
[ "$(basename "$deb")" = "polyexplore_${version}_${arch}.deb" ] || fail "file name $(basename "$deb")"

# --- control data ---
field() { dpkg-deb -f "$deb" "$1"; }
[ "$(field Package)" = polyexplore ] || fail "Package: $(field Package)"
[ "$(field Version)" = "$version" ] || fail "Version: $(field Version)"
depends=$(field Depends)
for d in liblcm1 liblcm-bin libsystemd0 libspdlog libcairo2 adduser iproute2; do
  [[ ", $depends" == *", $d"* ]] || fail "Depends lacks $d: $depends"
done
recommends=$(field Recommends)  # pex-spy: lcm.jar, jchart2d, a JRE with Swing
for d in liblcm-java libjchart2d-java default-jre; do
  [[ ", $recommends" == *", $d"* ]] || fail "Recommends lacks $d: $recommends"
done
dpkg-deb -e "$deb" "$tmp/control" || exit 1
for s in postinst prerm postrm; do
  [ -x "$tmp/control/$s" ] || fail "no executable $s"
  sh -n "$tmp/control/$s" || fail "$s: shell syntax"
done
grep -Eq '(adduser|useradd) --system.* polyexplore' "$tmp/control/postinst" || fail "postinst does not create the polyexplore system user"
# postinst run with getent/adduser stand-ins: makes the user when missing, only then
shim=$tmp/shim; mkdir -p "$shim"
printf '#!/bin/sh\nexit "${PEX_SHIM_GETENT:-2}"\n' >"$shim/getent"
printf '#!/bin/sh\necho "$*" >>"%s/adduser.calls"\n' "$tmp" >"$shim/adduser"
chmod +x "$shim"/*
PATH=$shim:$PATH PEX_SHIM_GETENT=2 sh "$tmp/control/postinst" configure || fail "postinst configure failed (no user yet)"
grep -q -- '--system.* polyexplore$' "$tmp/adduser.calls" 2>/dev/null || fail "postinst did not run adduser --system ... polyexplore: $(cat "$tmp/adduser.calls" 2>/dev/null)"
rm -f "$tmp/adduser.calls"
PATH=$shim:$PATH PEX_SHIM_GETENT=0 sh "$tmp/control/postinst" configure || fail "postinst configure failed (user there)"
[ ! -e "$tmp/adduser.calls" ] || fail "postinst ran adduser although the user exists"
! grep -Eq 'deluser|userdel' "$tmp/control/postinst" "$tmp/control/prerm" "$tmp/control/postrm" || fail "a maintainer script removes the user"
# conffiles: exactly the files under /etc
dpkg-deb --fsys-tarfile "$deb" | tar -t | sed -n 's#^\./etc/\(.*[^/]\)$#/etc/\1#p' | sort >"$tmp/etc_files"
sort "$tmp/control/conffiles" >"$tmp/conffiles"
diff "$tmp/etc_files" "$tmp/conffiles" >/dev/null || fail "conffiles differ from the files in /etc: $(diff "$tmp/etc_files" "$tmp/conffiles" | tr '\n' ' ')"
contents=$(dpkg-deb --contents "$deb")
grep -q 'pex-bench-\|_test$' <<<"$contents" && fail "benchmarks or tests packaged: $(grep -o '[^ ]*\(pex-bench-[^ ]*\|_test\)$' <<<"$contents" | tr '\n' ' ')"

# --- the files ---
dpkg -x "$deb" "$root" || exit 1
if [ -n "${PEX_PKG_DROP:-}" ]; then rm -f "$root$PEX_PKG_DROP"; fi
need() { [ -f "$root$1" ] || { fail "$1 missing"; return 1; }; }
same() { if need "$1"; then cmp -s "$2" "$root$1" || fail "$1 differs from ${2#"$src"/}"; fi; return 0; }

for p in $programs; do
  need /usr/bin/"$p" || continue
  [ -x "$root/usr/bin/$p" ] || fail "/usr/bin/$p not executable"
  "$root/usr/bin/$p" --help >/dev/null 2>&1 || fail "/usr/bin/$p --help fails (libraries?)"
done
n_bin=$(find "$root/usr/bin" -type f | wc -l)
[ "$n_bin" -eq "$(wc -w <<<"$programs")" ] || fail "/usr/bin holds $n_bin files, expected: $programs"

for u in "$src"/systemd/*.service "$src"/systemd/*.target "$src"/systemd/*.timer; do
  [ -e "$u" ] && same /lib/systemd/system/"$(basename "$u")" "$u"
done
for e in "$src"/systemd/*.env; do same /etc/polyexplore/"$(basename "$e")" "$e"; done
# configs, two layers: /usr/share/polyexplore/config/X.toml is config/X.toml (the
# defaults), /etc/polyexplore/X.toml the robot's overlay (config/robot/X.toml, else one
# setting no key), /usr/share/polyexplore/config/sim/X.toml overlays setting no key
keys_of() { grep -Ev '^[[:space:]]*(#.*)?$' "$1"; }  # the lines that set something
for c in "$src"/config/*.toml; do
  n=$(basename "$c")
  same /usr/share/polyexplore/config/"$n" "$c"
  if [ -f "$src/config/robot/$n" ]; then same /etc/polyexplore/"$n" "$src/config/robot/$n"
  elif need /etc/polyexplore/"$n"; then
    [ -z "$(keys_of "$root/etc/polyexplore/$n")" ] || fail "/etc/polyexplore/$n sets keys but there is no config/robot/$n"
  fi
  if need /usr/share/polyexplore/config/sim/"$n"; then
    [ -z "$(keys_of "$root/usr/share/polyexplore/config/sim/$n")" ] || fail "/usr/share/polyexplore/config/sim/$n sets keys"
  fi
done
for w in "$src"/worlds/*.wkt; do same /usr/share/polyexplore/worlds/"$(basename "$w")" "$w"; done
if need /usr/share/java/pex_types.jar; then
  classes=$(jar tf "$root/usr/share/java/pex_types.jar")
  for t in "$src"/lcmtypes/*.lcm; do
    n=$(basename "$t" .lcm); n=${n#pex_}
    grep -qx "pex/$n.class" <<<"$classes" || fail "pex_types.jar lacks pex/$n.class"
  done
fi

# the launchers name the installed types jar
for s in pex-spy pex-logplayer-gui; do
  grep -q '/usr/share/java/pex_types.jar' "$root/usr/bin/$s" 2>/dev/null || fail "/usr/bin/$s does not use /usr/share/java/pex_types.jar"
done

# --- the installed units, verified against the scratch root's programs ---
mkdir "$tmp/units"
cp "$root"/lib/systemd/system/* "$tmp/units/"
# every program a unit runs is in the package, or comes with a declared dependency
for exe in $(sed -n 's/^Exec[A-Za-z]*=[-@:+!]*\([^ ]*\).*/\1/p' "$tmp"/units/* | sort -u); do
  if [ -e "$root$exe" ]; then continue; fi
  case "$exe" in
    /usr/bin/lcm-logger) [[ "$depends" == *liblcm-bin* ]] || fail "$exe: liblcm-bin not in Depends" ;;
    /usr/bin/ip|/usr/sbin/ip|/sbin/ip|/bin/ip) [[ "$depends" == *iproute2* ]] || fail "$exe: iproute2 not in Depends" ;;
    *) fail "a unit runs $exe, which is neither in the package nor a known dependency" ;;
  esac
done
# The robot's values win in the installed tree: each daemon run as its unit runs it
# (ExecStart's arguments, paths into the scratch root) with --print-config. Every key
# the overlay in /etc sets is printed from there (file and line), every other one from
# /usr/share/polyexplore/config/X.toml or its default; with the simulator's overlays
# over /etc (README), every key from /usr/share or its default.
overlay_keys() {  # "key line" for each key an overlay sets, [section] as a prefix
  awk '/^[ \t]*\[/ { s = $0; gsub(/[][ \t]/, "", s); sub(/#.*/, "", s); next }
       /^[ \t]*[A-Za-z0-9_]+[ \t]*=/ { k = $0; sub(/[ \t]*=.*/, "", k); gsub(/[ \t]/, "", k);
                                      print (s == "" ? k : s "." k), NR }' "$1"
}
cp -a "$root/etc/polyexplore" "$tmp/etc-sim"
for f in "$root"/usr/share/polyexplore/config/sim/*.toml; do cp "$f" "$tmp/etc-sim/"; done
for u in "$tmp"/units/pex-*.service; do
  line=$(sed -n 's/^ExecStart=\(\/usr\/bin\/pex-[^ ]*\)\(.*\)/\1\2/p' "$u")
  [ -n "$line" ] || continue
  read -r -a argv <<<"$line"
  overlay=$(grep -o '/etc/polyexplore/[a-z_]*\.toml' <<<"$line")
  base=$(grep -o '/usr/share/polyexplore/config/[a-z_]*\.toml' <<<"$line")
  [ -n "$overlay" ] && [ -n "$base" ] || { fail "$(basename "$u"): ExecStart does not name /usr/share/polyexplore/config/X.toml and /etc/polyexplore/X.toml: $line"; continue; }
  [[ "$line" == *"--config $base --config $overlay"* ]] || fail "$(basename "$u"): the overlay is not read after the defaults: $line"
  for setup in robot sim; do
    etc=$root/etc/polyexplore; [ $setup = sim ] && etc=$tmp/etc-sim
    args=("${argv[@]:1}"); args=("${args[@]//\/etc\/polyexplore/$etc}"); args=("${args[@]//\/usr\/share/$root/usr/share}")
    out=$("$root${argv[0]}" --print-config "${args[@]}" 2>&1) || { fail "$(basename "$u") ($setup): --print-config failed: $out"; continue; }
    from_etc=$(grep -c "# $etc/" <<<"$out")
    expected=0
    while read -r key n; do
      expected=$((expected + 1))
      grep -q "^$key = .*# $etc/$(basename "$overlay"):$n\$" <<<"$out" \
        || fail "$(basename "$u") ($setup): $key, set in $overlay line $n, is printed as: $(grep "^$key = " <<<"$out")"
    done < <(overlay_keys "$etc/$(basename "$overlay")")
    [ "$from_etc" = "$expected" ] || fail "$(basename "$u") ($setup): $from_etc keys printed from $etc, the overlay sets $expected"
    grep -v '^#' <<<"$out" | grep -Ev "# ($root/usr/share/polyexplore/config/[a-z_]+\.toml:[0-9]+|$etc/[a-z_]+\.toml:[0-9]+|default)\$" \
      | head -n 3 | while read -r l; do fail "$(basename "$u") ($setup): a value from elsewhere: $l"; done
    if [ $setup = robot ]; then
      case $(basename "$u") in
        pex-base-driver.service) want='can_transport = "socketcan"' ;;
        pex-lidar-reader.service) want='host = "192.168.0.1"' ;;
        pex-explorer.service) want='autostart = false' ;;
        *) want= ;;
      esac
      [ -z "$want" ] || grep -q "^$want " <<<"$out" || fail "$(basename "$u"): the robot's $want lost: $(grep "^${want%% *} " <<<"$out")"
    fi
    clock=$(sed -n 's/^clock = "\([a-z]*\)".*/\1/p' <<<"$out")
    if grep -q '^clock = "sim"' "$root$base"; then  # the daemons on the simulator's clock in the defaults
      [ $setup = robot ] && [ "$clock" != system ] && fail "$(basename "$u"): the robot runs on clock = \"$clock\""
      [ $setup = sim ] && [ "$clock" != sim ] && fail "$(basename "$u") with the simulator's overlays: clock = \"$clock\""
    fi
    robot_values=$((robot_values + expected))
  done
  if [ "$(basename "$u")" = pex-sim.service ]; then  # the world it names is installed
    w=$(sed -n 's/^world_file = "\([^"]*\)".*/\1/p' <<<"$out")
    [ -f "$w" ] || fail "pex-sim's world_file $w is not in the package"
  fi
done
echo "print-config as the units run: $robot_values keys printed from the /etc overlays"
sed -i -e "s#=\([-@:+!]*\)/usr/bin/pex-#=\1$root/usr/bin/pex-#" -e "s#=\([-@:+!]*\)/usr/lib/polyexplore/#=\1$root/usr/lib/polyexplore/#" "$tmp"/units/*
out=$(systemd-analyze verify "$tmp"/units/* 2>&1 | grep -F "$tmp" || true)
[ -z "$out" ] || fail "systemd-analyze verify: $out"

if ((fails)); then echo "$fails failure(s) in $(basename "$deb")"; exit 1; fi
echo "$(basename "$deb"): $(wc -l <<<"$contents") entries, every check passed"
