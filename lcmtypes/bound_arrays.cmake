# Run after lcm-gen (cmake -P bound_arrays.cmake FILE...): hardens the generated decoders
# against hostile length fields (docs/RELIABILITY.md).
#
# Arrays: lcm-gen's C++ decoder resizes a variable-length array to the length field it
# just read and only then checks that the bytes are there, so a tiny hostile message with
# a huge length field makes the receiver allocate (and zero) gigabytes. This inserts a
# check before every resize: a length larger than the bytes left fails the decode (-1),
# as for any other truncated message. Every element of a one-dimensional array takes at
# least one byte, so no real message is refused; a two-dimensional array whose rows are
# empty (e.g. observations_t with num_sources = 0) takes no bytes per row and is refused
# when it has more rows than bytes are left -- none of hbirl's services accepts such a
# message anyway (no sources, no symbols, no actions). What a decode allocates is thus at
# most a small multiple of the bytes received.
#
# Strings: the decoder checks `len > maxlen - pos` and then copies `len - 1` bytes; a
# length of 0 or below (INT_MIN) passes the check and the copy's size wraps to ~2^64
# (a crash). An encoded string always counts its terminating zero, so a length below 1
# now fails the decode.
#
# If a future lcm-gen writes these lines differently, the build stops here rather than
# ship unbounded decoders.
math(EXPR last "${CMAKE_ARGC} - 1")
foreach(i RANGE 3 ${last})
  set(file "${CMAKE_ARGV${i}}")
  file(READ "${file}" text)
  string(REGEX REPLACE "([ \t]*)(this->[A-Za-z0-9_]+(\\[a[0-9]+\\])*)\\.resize\\((this->[A-Za-z0-9_]+)\\);"
         "\\1if ((\\4) < 0 || (\\4) > maxlen - pos) return -1;  // hbirl: bound_arrays.cmake\n\\1\\2.resize(\\4);" text "${text}")
  string(REGEX REPLACE "if\\((__[A-Za-z0-9_]+) > maxlen - pos\\) return -1;"
         "if ((\\1) < 1 || (\\1) > maxlen - pos) return -1;  // hbirl: bound_arrays.cmake (strings)" text "${text}")
  # Every resize and every string copy must now be right after one of the checks above.
  foreach(what resize assign)
    string(REGEX MATCHALL "\\.${what}\\(" all "${text}")
    string(REGEX MATCHALL "bound_arrays.cmake[^\n]*\n[^\n]*\\.${what}\\(" bounded "${text}")
    list(LENGTH all n_all)
    list(LENGTH bounded n_bounded)
    if(NOT n_all EQUAL n_bounded)
      message(FATAL_ERROR "bound_arrays.cmake: ${file} has ${n_all} .${what}() calls but only ${n_bounded} "
                          "behind a length check: lcm-gen writes its decoders differently now; update this patch")
    endif()
  endforeach()
  file(WRITE "${file}" "${text}")
endforeach()
