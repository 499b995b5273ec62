# The README quotes tests/c/readme_example.c verbatim: fails if the two drift apart.
# -DREADME=... -DEXAMPLE=...
file(READ ${README} readme)
file(READ ${EXAMPLE} example)
string(FIND "${readme}" "```c\n${example}```" at)
if(at EQUAL -1)
  message(FATAL_ERROR "${README} does not quote ${EXAMPLE} verbatim in a ```c block")
endif()
