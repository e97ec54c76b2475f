# spy_table WINDOW: lcm-spy's channel table in window WINDOW (an xdotool id) on $DISPLAY,
# tab-separated, as Ctrl+C copies it; 1 if no copy landed in 5 s. The clipboard holds a
# marker first, and the copy has landed when the marker is gone (Java takes the
# clipboard a moment after the keys): never the last table read again.
# Sourced by tests/spy/spy_gui.sh and tests/systemd/nspawn_boot.sh (pex-spy over ssh -X).
spy_table() {
  printf 'pex-no-copy' | xclip -selection clipboard -i >/dev/null 2>&1  # its server stays until Java copies
  xdotool windowfocus "$1" mousemove --window "$1" 60 28 click 1 key ctrl+a ctrl+c 2>/dev/null
  local t
  for _ in $(seq 50); do
    t=$(timeout 5 xclip -selection clipboard -o 2>/dev/null)
    [ -n "$t" ] && [ "$t" != pex-no-copy ] && { printf '%s\n' "$t"; return 0; }
    sleep 0.1
  done
  return 1
}
