# cmake -DIN=index.html -DOUT=viewer_page.cpp -P embed_page.cmake: the page as a C++ string.
file(READ ${IN} page)
string(FIND "${page}" ")PEXPAGE\"" clash)
if(NOT clash EQUAL -1)
  message(FATAL_ERROR "${IN} contains the raw string's delimiter )PEXPAGE\"")
endif()
file(WRITE ${OUT} "// Generated from ${IN} by embed_page.cmake: do not edit.\nnamespace pex::viewer {\nextern const char* const kPage;\nconst char* const kPage = R\"PEXPAGE(${page})PEXPAGE\";\n}  // namespace pex::viewer\n")
