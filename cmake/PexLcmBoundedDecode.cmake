# cmake -DDIR=<folder of lcm-gen C++ headers> -P PexLcmBoundedDecode.cmake
#
# Bounds the allocations of lcm-gen's C++ decoders by the bytes of the message
# (issue 12). lcm-gen sizes every variable-length array from the count field
# the packet carries, before it looks at how many bytes are left: one 173-byte
# polygon_map_t claiming 10^7 rings cost the explorer 880 MB, and a negative
# count made std::vector throw (an "error", not rejected input).
#
# Every element of an array takes a known minimum of encoded bytes, so before
# each resize this inserts
#     if (this->N < 0 || this->N > (maxlen - pos) / MIN) return -1;
# where MIN is, by what the array holds:
#   primitive  its encoded size (int8_t/byte/boolean 1, int16_t 2, int32_t/float 4, int64_t/double 8)
#   string     5 (4-byte length and at least the terminating NUL)
#   struct     the encoded size of an empty one (its _getEncodedSizeNoHash()
#              with every count 0 and every string ""), at least 1
#   row        1: a row of a 2-D array (T a[n][m]). Rows of m = 0 take no bytes
#              at all, so more rows than bytes left are refused though LCM could
#              encode them; none of our types has such an array.
# and a string length < 1 is refused too (lcm-gen takes length - 1 as the
# size_t to copy). A vector then never holds more elements than the remaining
# bytes could encode: a message of S bytes allocates at most
# sizeof(element) / MIN times S per nesting level (docs/channels.md has k for
# our types).
#
# Why patch the generated code rather than wrap it: a pre-validator walking the
# encoding would be a second decoder per type to keep in step with lcm-gen; the
# guard sits where the allocation is, and the type's own code stays the only
# decoder. Why cmake -P: the project builds from Debian's packages only, and
# CMake is the one scripting tool the build has anyway.
#
# The patch understands the shapes lcm-gen 1.3.1 (Debian 12) writes. Anything in
# a _decodeNoHash it does not recognise (a resize or assign it cannot guard, any
# line not known to be free of allocation) fails the build, so a future lcm-gen
# cannot bypass it silently.
cmake_minimum_required(VERSION 3.20)

if(NOT DIR OR NOT IS_DIRECTORY "${DIR}")
  message(FATAL_ERROR "PexLcmBoundedDecode: DIR '${DIR}' is not a folder of generated headers")
endif()
set(marker "// pex: array counts bounded by the bytes left (cmake/PexLcmBoundedDecode.cmake)")

# Encoded bytes of one element, by lcm_coretypes' __<type>_decode_array name.
set(min_int8_t 1)
set(min_byte 1)
set(min_boolean 1)
set(min_int16_t 2)
set(min_int32_t 4)
set(min_float 4)
set(min_int64_t 8)
set(min_double 8)

function(fail header line_no text why)
  swap_specials("${text}" text FALSE)
  message(FATAL_ERROR "PexLcmBoundedDecode: ${header}:${line_no}: ${why}:\n  ${text}\n"
          "lcm-gen wrote a decoder this patch does not understand; the build stops rather "
          "than ship a decoder whose allocations are unbounded. Teach cmake/PexLcmBoundedDecode.cmake "
          "the new shape.")
endfunction()

# CMake lists split on ';' and nest on '[' ']': both are everywhere in C++, so
# they travel as control characters (never in lcm-gen's output) while the file
# is a list of lines.
set(specials ";[]\\")  # travel as the control characters 1, 2, 3, 4
string(ASCII 1 sc)
string(ASCII 2 lb)
string(ASCII 3 rb)
function(swap_specials text out to_control)
  foreach(i RANGE 0 3)
    string(SUBSTRING "${specials}" ${i} 1 special)
    math(EXPR code "${i} + 1")
    string(ASCII ${code} control)
    if(to_control)
      string(REPLACE "${special}" "${control}" text "${text}")
    else()
      string(REPLACE "${control}" "${special}" text "${text}")
    endif()
  endforeach()
  set(${out} "${text}" PARENT_SCOPE)
endfunction()

function(to_lines text out)
  string(ASCII 1 first)
  string(ASCII 4 last)
  if(text MATCHES "[${first}-${last}]")
    message(FATAL_ERROR "PexLcmBoundedDecode: a header holds control characters 1-4")
  endif()
  swap_specials("${text}" text TRUE)
  string(REPLACE "\n" ";" text "${text}")
  set(${out} "${text}" PARENT_SCOPE)
endfunction()

function(from_lines lines out)
  string(REPLACE ";" "\n" text "${lines}")
  swap_specials("${text}" text FALSE)
  set(${out} "${text}" PARENT_SCOPE)
endfunction()

# An array member path such as this->in2[a0][a1], its brackets swapped.
set(path_re "this->[A-Za-z_][A-Za-z_0-9]*(${lb}[A-Za-z_0-9]+${rb})*")

# The other lines of lcm-gen's _decodeNoHash: none of them allocates.
set(known_lines
  "^int [A-Za-z_0-9]+::_decodeNoHash\\(const void \\*buf, int offset, int maxlen\\)$"
  "^ *[{}]?$"
  "^    int pos = 0, tlen${sc}$"
  "^ *tlen = __[a-z0-9_]+_decode_array\\(buf, offset \\+ pos, maxlen - pos, &[^()]+, [^()]+\\)${sc}$"
  "^ *tlen = ${path_re}\\._decodeNoHash\\(buf, offset \\+ pos, maxlen - pos\\)${sc}$"
  "^ *if\\(tlen < 0\\) return tlen${sc} else pos \\+= tlen${sc}$"
  "^ *int32_t __[A-Za-z_0-9]+${sc}$"
  "^ *pos \\+= __[A-Za-z_0-9]+${sc}$"
  "^ *if\\((this->[A-Za-z_0-9]+|[0-9]+)\\) {$"
  "^ *for \\(int a[0-9]+ = 0${sc} a[0-9]+ < (this->[A-Za-z_0-9]+|[0-9]+)${sc} a[0-9]+\\+\\+\\) {$"
  "^ *return pos${sc}$")

function(patch_header header)
  file(READ "${header}" text)
  string(FIND "${text}" "${marker}" seen)
  if(NOT seen EQUAL -1)
    message(FATAL_ERROR "PexLcmBoundedDecode: ${header} is patched already (lcm-gen did not rewrite it?)")
  endif()
  to_lines("${text}" lines)
  list(LENGTH lines n)
  math(EXPR last "${n} - 1")
  set(out)
  set(in_decode FALSE)
  set(decode_bodies 0)
  set(guards 0)
  set(include_added FALSE)
  set(length_checked FALSE)  # the previous line was a patched string length check
  foreach(i RANGE 0 ${last})
    list(GET lines ${i} line)
    math(EXPR line_no "${i} + 1")
    if(line STREQUAL "#include <lcm/lcm_coretypes.h>")
      list(APPEND out "${line}" "" "${marker}" "#include <type_traits>")
      set(include_added TRUE)
      continue()
    endif()
    if(line MATCHES "^int [A-Za-z_0-9]+::_decodeNoHash\\(const void \\*buf, int offset, int maxlen\\)$")
      set(in_decode TRUE)
      math(EXPR decode_bodies "${decode_bodies} + 1")
    elseif(in_decode AND line STREQUAL "}")
      set(in_decode FALSE)
    endif()
    if(NOT in_decode)
      list(APPEND out "${line}")
      continue()
    endif()

    # String lengths: lcm-gen refuses only lengths beyond the bytes left.
    if(line MATCHES "^( *)if\\((__[A-Za-z_0-9]+) > maxlen - pos\\) return -1${sc}$")
      list(APPEND out "${CMAKE_MATCH_1}if(${CMAKE_MATCH_2} < 1 || ${CMAKE_MATCH_2} > maxlen - pos) return -1${sc}")
      set(length_checked TRUE)
      continue()
    endif()
    if(line MATCHES "\\.assign\\(")
      if(NOT length_checked)
        fail("${header}" ${line_no} "${line}" "a string assign without the length check before it")
      endif()
      set(length_checked FALSE)
      list(APPEND out "${line}")
      continue()
    endif()
    set(length_checked FALSE)

    if(line MATCHES "resize")
      if(line MATCHES "^ *${path_re}\\.resize\\([0-9]+\\)${sc}$")
        # A fixed dimension (T a[3][n]): bounded by the type itself.
        list(APPEND out "${line}")
        continue()
      endif()
      if(NOT line MATCHES "^( *)(${path_re})\\.resize\\(this->([A-Za-z_][A-Za-z_0-9]*)\\)${sc}$")
        fail("${header}" ${line_no} "${line}" "a resize the patch cannot guard")
      endif()
      set(indent "${CMAKE_MATCH_1}")
      set(array "${CMAKE_MATCH_2}")
      set(count "this->${CMAKE_MATCH_4}")
      # What the array holds decides the minimum bytes per element: the next
      # line decodes the elements at once (primitives) or opens a loop over
      # them, whose first line tells strings, structs and rows apart.
      math(EXPR j "${i} + 1")
      math(EXPR k "${i} + 2")
      set(next "")
      set(after "")
      if(j LESS n)
        list(GET lines ${j} next)
      endif()
      if(k LESS n)
        list(GET lines ${k} after)
      endif()
      set(min "")
      set(struct_min "")
      if(next MATCHES "^ *tlen = __([a-z0-9_]+)_decode_array\\(buf, offset \\+ pos, maxlen - pos, &${array}${lb}0${rb}, ${count}\\)${sc}$")
        set(min "${min_${CMAKE_MATCH_1}}")
        if(min STREQUAL "")
          fail("${header}" ${line_no} "${next}" "an array of an unknown primitive '${CMAKE_MATCH_1}'")
        endif()
      elseif(next MATCHES "^ *for \\(int (a[0-9]+) = 0${sc} a[0-9]+ < ${count}${sc} a[0-9]+\\+\\+\\) {$")
        set(loop_var "${CMAKE_MATCH_1}")
        if(after MATCHES "^ *int32_t __elem_len${sc}$")
          set(min 5)
        elseif(after MATCHES "^ *tlen = (${path_re})\\._decodeNoHash\\(buf, offset \\+ pos, maxlen - pos\\)${sc}$")
          # The element's type, named through the path with every index 0
          # (unevaluated: nothing is read).
          string(REGEX REPLACE "${lb}a[0-9]+${rb}" "${lb}0${rb}" elem "${CMAKE_MATCH_1}")
          set(min "(pex_min_bytes_ > 0 ? pex_min_bytes_ : 1)")
          set(struct_min "const int pex_min_bytes_ = std::decay_t<decltype(${elem})>()._getEncodedSizeNoHash()${sc}")
        elseif(after MATCHES "^ *${array}${lb}${loop_var}${rb}\\.resize\\(" OR after MATCHES "^ *if\\(")
          set(min 1)
        endif()
      endif()
      if(min STREQUAL "")
        fail("${header}" ${line_no} "${line}\n  ${next}\n  ${after}" "a resize followed by a decode the patch does not know")
      endif()
      set(guard "if (${count} < 0 || ${count} > (maxlen - pos) / ${min}) return -1${sc}")
      if(struct_min)
        list(APPEND out "${indent}{" "${indent}    ${struct_min}" "${indent}    ${guard}" "${indent}}")
      else()
        list(APPEND out "${indent}${guard}")
      endif()
      list(APPEND out "${line}")
      math(EXPR guards "${guards} + 1")
      continue()
    endif()
    # Whatever else the decoder does must be one of the lines known not to
    # allocate: anything new (a std::string built another way, a push_back, a
    # helper call) stops the build instead of slipping through.
    set(known FALSE)
    foreach(re IN LISTS known_lines)
      if(line MATCHES "${re}")
        set(known TRUE)
        break()
      endif()
    endforeach()
    if(NOT known)
      fail("${header}" ${line_no} "${line}" "a line the patch does not know in a decoder")
    endif()
    list(APPEND out "${line}")
  endforeach()

  if(NOT include_added)
    message(FATAL_ERROR "PexLcmBoundedDecode: ${header}: no '#include <lcm/lcm_coretypes.h>' to add <type_traits> after")
  endif()
  if(NOT decode_bodies EQUAL 1)
    message(FATAL_ERROR "PexLcmBoundedDecode: ${header}: ${decode_bodies} _decodeNoHash definitions, expected 1")
  endif()
  from_lines("${out}" patched)
  file(WRITE "${header}" "${patched}")
  set(guards_total ${guards} PARENT_SCOPE)
endfunction()

file(GLOB headers "${DIR}/*.hpp")
if(NOT headers)
  message(FATAL_ERROR "PexLcmBoundedDecode: no headers in ${DIR}")
endif()
set(total 0)
foreach(h ${headers})
  patch_header("${h}")
  math(EXPR total "${total} + ${guards_total}")
endforeach()
list(LENGTH headers nh)
message(STATUS "PexLcmBoundedDecode: ${total} array counts guarded in ${nh} headers")
