# Build-time script: turns a program's --help text into a man page, so `man vp_firmware_app`
# always shows the options of the installed binary (a tiny stand-in for help2man).
#
#   cmake -DHELP=help.txt -DOUT=prog.1 -DNAME=prog -DSECTION=1 -DSUMMARY="one line"
#         -DVERSION=0.1.0 [-DEXTRA=extra.roff] -P HelpToMan.cmake
#
# The help text is set verbatim (no-fill) under DESCRIPTION; EXTRA, if given, is appended
# as raw roff (FILES, SEE ALSO sections).

foreach(var HELP OUT NAME SECTION SUMMARY VERSION)
  if(NOT DEFINED ${var})
    message(FATAL_ERROR "packaging/HelpToMan.cmake: -D${var}=... is required")
  endif()
endforeach()
if(NOT EXISTS "${HELP}")
  message(FATAL_ERROR "packaging/HelpToMan.cmake: help text ${HELP} does not exist")
endif()

file(READ "${HELP}" help)
if(help STREQUAL "")
  message(FATAL_ERROR "packaging/HelpToMan.cmake: ${HELP} is empty (did `${NAME} --help` print "
                      "to stderr?)")
endif()
# roff escapes: backslash first, then minus signs (so options copy as ASCII '-'), then
# control characters at the start of a line.
string(REPLACE "\\" "\\e" help "${help}")
string(REPLACE "-" "\\-" help "${help}")
string(REGEX REPLACE "(^|\n)([.'])" "\\1\\\\&\\2" help "${help}")

string(TOUPPER "${NAME}" title)
string(REPLACE "-" "\\-" summary "${SUMMARY}")
# (string(APPEND), not a list: the help text may contain semicolons)
set(page ".TH ${title} ${SECTION} \"\" \"vehicle-perception ${VERSION}\" \"vehicle-perception\"\n")
string(APPEND page ".SH NAME\n${NAME} \\- ${summary}\n")
string(APPEND page ".SH DESCRIPTION\nThe text of\n.B ${NAME} \\-\\-help:\n.PP\n.nf\n")
string(APPEND page "${help}\n.fi\n")
if(DEFINED EXTRA AND NOT EXTRA STREQUAL "")
  file(READ "${EXTRA}" extra)
  string(APPEND page "${extra}")
endif()
file(WRITE "${OUT}" "${page}")
