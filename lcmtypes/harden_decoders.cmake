# Run after lcm-gen (cmake -DDIR=<folder of the generated C++ headers> -P this file): hardens LCM
# 1.3.1's generated decoders against hostile lengths, whatever the message layout.
#  - a string's length (which includes the NUL) below 1 made them call assign(p, len - 1):
#    std::length_error for 0, a 2 GiB read past the buffer (segfault) for INT32_MIN;
#  - an array count was used to allocate before anything checked it against the bytes left:
#    negative counts threw, large ones allocated gigabytes. Every element takes at least one
#    encoded byte, so a count above the bytes left is malformed.
# common/decode.hpp still catches anything they throw; this keeps them from reading out of
# bounds, which no catch can undo.
file(GLOB headers "${DIR}/*.hpp")
if(NOT headers)
  message(FATAL_ERROR "harden_decoders: no headers in ${DIR}")
endif()
foreach(header ${headers})
  file(READ "${header}" text)
  string(REGEX REPLACE "if\\(__([A-Za-z0-9_]+)_len__ > maxlen - pos\\) return -1;"
         "if(__\\1_len__ < 1 || __\\1_len__ > maxlen - pos) return -1;" text "${text}")
  string(REGEX REPLACE "\n( *)this->([A-Za-z0-9_]+)\\.resize\\(this->([A-Za-z0-9_]+)\\);"
         "\n\\1if(this->\\3 < 0 || this->\\3 > maxlen - pos) return -1;\n\\1this->\\2.resize(this->\\3);"
         text "${text}")
  file(WRITE "${header}" "${text}")
endforeach()
