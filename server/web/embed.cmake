# Writes OUTPUT, a C++ file defining fenestra::WebFiles() (server/web_files.h) with the bytes
# of index.html, app.js and app.css in WEB_DIR. Run as `cmake -DWEB_DIR=... -DOUTPUT=... -P`.
set(body "")
set(table "")
foreach(name index.html app.js app.css)
  get_filename_component(extension "${name}" LAST_EXT)
  if(extension STREQUAL ".html")
    set(type "text/html")
  elseif(extension STREQUAL ".js")
    set(type "text/javascript")
  else()
    set(type "text/css")
  endif()
  file(READ "${WEB_DIR}/${name}" hex HEX)
  string(LENGTH "${hex}" hex_length)
  math(EXPR bytes "${hex_length} / 2")
  string(REGEX REPLACE "([0-9a-f][0-9a-f])" "'\\\\x\\1'," chars "${hex}")
  string(MAKE_C_IDENTIFIER "${name}" id)
  string(APPEND body "const char k_${id}[] = {${chars} 0};\n")
  string(APPEND table "    {\"/${name}\", \"${type}; charset=utf-8\", {k_${id}, ${bytes}}},\n")
endforeach()
file(WRITE "${OUTPUT}.tmp" "// Made by server/web/embed.cmake from server/web/; do not edit.\n"
  "#include \"server/web_files.h\"\n\nnamespace fenestra {\nnamespace {\n${body}}  // namespace\n\n"
  "std::span<const WebFile> WebFiles() {\n  static const WebFile kFiles[] = {\n${table}  };\n"
  "  return kFiles;\n}\n\n}  // namespace fenestra\n")
file(COPY_FILE "${OUTPUT}.tmp" "${OUTPUT}" ONLY_IF_DIFFERENT)
file(REMOVE "${OUTPUT}.tmp")
