# Run after lcm-gen (cmake -DDIR=<dir of generated .hpp> -P harden_cpp.cmake). lcm-gen 1.3.1's C++
# string decoding checks a string's length only against the bytes left ("len > maxlen - pos"),
# then copies len - 1 bytes: a length of 0 threw std::length_error (caught by decode_message), and
# a length of INT32_MIN wrapped len - 1 to INT32_MAX, so std::string::assign read 2 GiB past the
# buffer: one 79-byte OPERATOR_CMD killed alight-autonomy with SIGSEGV (found by
# fuzz/lcm_operator_cmd; the same in every type with a string). An LCM string always has its
# terminating NUL, so every length below 1 is refused here, in every generated type.
file(GLOB headers ${DIR}/*.hpp)
foreach(h ${headers})
  file(READ ${h} text)
  string(REGEX REPLACE "if\\(__([A-Za-z0-9_]+)_len__ > maxlen - pos\\) return -1;"
                       "if(__\\1_len__ < 1 || __\\1_len__ > maxlen - pos) return -1;" text "${text}")
  file(WRITE ${h} "${text}")
endforeach()
