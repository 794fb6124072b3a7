# Run after lcm-gen (cmake -P bound_arrays.cmake FILE...): hardens the generated decoders.
# lcm-gen's C++ decoder resizes a variable-length array to the length field it just read
# and only then checks that the bytes are there, so a tiny hostile message with a huge
# length field makes the receiver allocate (and zero) gigabytes. This inserts a check
# before every resize: a length larger than the bytes left fails the decode (-1), as for
# any other truncated message. Every element of a one-dimensional array takes at least
# one byte, so no real message is refused; a two-dimensional array whose rows are empty
# (e.g. observations_t with num_sources = 0) takes no bytes per row and is refused when
# it has more rows than bytes are left -- none of hbirl's services accepts such a
# message anyway (no sources, no symbols, no actions).
math(EXPR last "${CMAKE_ARGC} - 1")
foreach(i RANGE 3 ${last})
  set(file "${CMAKE_ARGV${i}}")
  file(READ "${file}" text)
  string(REGEX REPLACE "([ \t]*)(this->[A-Za-z0-9_]+(\\[a[0-9]+\\])*)\\.resize\\((this->[A-Za-z0-9_]+)\\);"
         "\\1if ((\\4) < 0 || (\\4) > maxlen - pos) return -1;  // hbirl: bound_arrays.cmake\n\\1\\2.resize(\\4);" text "${text}")
  file(WRITE "${file}" "${text}")
endforeach()
