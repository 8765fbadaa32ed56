# cmake -DSPV=file.spv -DOUT=file.cpp -DIDENT=name -P embed_spirv.cmake
# Writes the SPIR-V words of SPV as a C++ array (SPIR-V is a stream of little-endian words).
file(READ "${SPV}" hex HEX)
string(LENGTH "${hex}" len)
math(EXPR rem "${len} % 8")
if(NOT rem EQUAL 0 OR len EQUAL 0)
  message(FATAL_ERROR "${SPV} is not a whole number of 32-bit words")
endif()
# Regroup each 4 bytes (8 hex digits, little-endian) into one 0x........u literal.
string(REGEX REPLACE "(..)(..)(..)(..)" "0x\\4\\3\\2\\1u," words "${hex}")
string(REGEX REPLACE "(([^,]*,){8})" "\\1\n" words "${words}")
math(EXPR count "${len} / 8")
file(WRITE "${OUT}" "// Generated from ${SPV}; do not edit.\n#include <cstddef>\n#include <cstdint>\nnamespace hemo::shaders {\nextern const std::uint32_t ${IDENT}_words[] = {\n${words}\n};\nextern const std::size_t ${IDENT}_count = ${count};\n}\n")
