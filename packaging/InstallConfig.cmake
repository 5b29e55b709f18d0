# Install-time script (install(SCRIPT) from packaging/CMakeLists.txt): writes the installed
# configuration and the systemd unit with the absolute paths of this installation.
#
# The repository's config/default.yaml names its files relative to the config's folder
# (../models/..., ../tests/fixtures/dtm/...). Installed as /etc/vp/vp.yaml those would
# resolve under /etc, so every such path is rewritten to the installed data folder
# (<prefix>/share/vp/...). A relative path left over after the rewrite is an error: a new
# config key pointing at a new file needs the file installed and a mapping below.
#
# Variables (set by the install(CODE) line before this script):
#   VP_SOURCE_CONFIG   config/default.yaml            VP_UNIT_TEMPLATE  the .service.in
#   VP_CONFIG_DIR      absolute, e.g. /etc/vp          VP_UNIT_DIR       absolute unit folder
#   VP_CONFIG_NAME     vp.yaml                         VP_UNIT_NAME      vehicle-perception.service
#   VP_DATA_SUBDIR     share/vp (under the prefix)     VP_ENV_FILE       /etc/default/...
#   VP_BIN_SUBDIR      bin (under the prefix)          VP_DOC_SUBDIR     share/doc/<package>
#   VP_LIBARCH         multiarch triplet of the build  VP_WORK_DIR       where to write
#   VP_WITH_UNIT       ON: also write the unit

foreach(var VP_SOURCE_CONFIG VP_CONFIG_DIR VP_CONFIG_NAME VP_DATA_SUBDIR VP_BIN_SUBDIR
            VP_LIBARCH VP_WORK_DIR VP_ENV_FILE VP_DOC_SUBDIR)
  if(NOT DEFINED ${var})
    message(FATAL_ERROR "packaging/InstallConfig.cmake: ${var} is not set")
  endif()
endforeach()

set(prefix "${CMAKE_INSTALL_PREFIX}")
set(data_dir "${prefix}/${VP_DATA_SUBDIR}")
set(VP_BINDIR "${prefix}/${VP_BIN_SUBDIR}")
set(VP_DOCDIR "${prefix}/${VP_DOC_SUBDIR}")
set(VP_CONFIG_FILE "${VP_CONFIG_DIR}/${VP_CONFIG_NAME}")

# --- the configuration --------------------------------------------------------------------
file(READ "${VP_SOURCE_CONFIG}" text)
# Repository path (relative to config/)  ->  installed path.
set(mappings
  "../models/|${data_dir}/models/"
  "../tests/fixtures/dtm/|${data_dir}/dtm/")
foreach(pair IN LISTS mappings)
  string(REPLACE "|" ";" pair "${pair}")
  list(GET pair 0 from)
  list(GET pair 1 to)
  string(REPLACE ": ${from}" ": ${to}" text "${text}")
  string(REPLACE ": \"${from}" ": \"${to}" text "${text}")
endforeach()
# Library folders (e.g. the DDS security plugins) of the package's architecture.
string(REGEX REPLACE "/usr/lib/[a-z0-9_]+-linux-gnu[a-z]*/" "/usr/lib/${VP_LIBARCH}/" text "${text}")

# Check: no value may still be a relative path; every rewritten file must be installed.
string(REPLACE ";" "\\;" text_escaped "${text}")
string(REPLACE "\n" ";" lines "${text_escaped}")
set(line_number 0)
set(problems "")
foreach(line IN LISTS lines)
  math(EXPR line_number "${line_number} + 1")
  string(REGEX REPLACE "#.*$" "" value_part "${line}")
  if(value_part MATCHES ":[ \t]+[\"']?(\\.\\.?/[^ \t\"']*)")
    string(APPEND problems "\n  line ${line_number}: relative path ${CMAKE_MATCH_1}")
  endif()
  if(value_part MATCHES ":[ \t]+[\"']?(${data_dir}/[^ \t\"']*)")
    if(NOT EXISTS "$ENV{DESTDIR}${CMAKE_MATCH_1}")
      string(APPEND problems "\n  line ${line_number}: ${CMAKE_MATCH_1} is not installed")
    endif()
  endif()
endforeach()
if(problems)
  message(FATAL_ERROR "packaging/InstallConfig.cmake: the installed ${VP_CONFIG_FILE} (from "
                      "${VP_SOURCE_CONFIG}) would be broken:${problems}\nInstall the file "
                      "(packaging/CMakeLists.txt) and add its folder to the mappings here.")
endif()

set(header "# Installed by the vehicle-perception package as ${VP_CONFIG_FILE} (a conffile: your\n"
           "# changes survive upgrades). Generated from the repository's config/default.yaml with\n"
           "# its relative paths rewritten to ${data_dir}/. The terrain model below is a\n"
           "# small SAMPLE (Madison, WI, UTM 16N): set terrain.dtm_path, origin and camera for your\n"
           "# site and camera before enabling the service (docs: ${VP_DOCDIR}/deployment.md).\n#\n")
string(JOIN "" header ${header})
file(MAKE_DIRECTORY "${VP_WORK_DIR}")
file(WRITE "${VP_WORK_DIR}/${VP_CONFIG_NAME}" "${header}${text}")
file(INSTALL DESTINATION "${VP_CONFIG_DIR}" TYPE FILE PERMISSIONS OWNER_READ OWNER_WRITE
     GROUP_READ WORLD_READ FILES "${VP_WORK_DIR}/${VP_CONFIG_NAME}")

# --- the systemd unit ---------------------------------------------------------------------
if(VP_WITH_UNIT)
  set(VP_ENV_FILE "${VP_ENV_FILE}")
  configure_file("${VP_UNIT_TEMPLATE}" "${VP_WORK_DIR}/${VP_UNIT_NAME}" @ONLY)
  file(INSTALL DESTINATION "${VP_UNIT_DIR}" TYPE FILE PERMISSIONS OWNER_READ OWNER_WRITE
       GROUP_READ WORLD_READ FILES "${VP_WORK_DIR}/${VP_UNIT_NAME}")
endif()
