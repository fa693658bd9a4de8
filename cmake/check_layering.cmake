# The folder dependency rule, checked (ctest: folder_layering, label unit; docs/architecture.md, "Layers").
#   cmake -DSOURCE_DIR=<tree> -DLINKS=<build>/layering/links.cmake -P cmake/check_layering.cmake
# Fails when
#   - a file of src/<folder>/ or esi/ includes "<folder>/..." of a library its own library may not use (the
#     table below, followed down: what a library may use, it may include, and what that one may use too);
#   - the table and the CMake link lists (written by cmake/layering.cmake) disagree: an arrow of the table
#     that CMake does not link, or a link of CMake the table does not allow.
# -DINJECT=<file>=<include> pretends that one more include is there (the test that the check can fail).

cmake_minimum_required(VERSION 3.22)

# ---- The rule: which library may use which (direct arrows). A library of a folder is named after it; the
# program vecat of src/cli is "cli"; src/cia402 holds three libraries, motion (pure models), drive_core
# (the drive without EtherCAT) and cia402 (its CoE adapter).
set(LAYER_common "")
set(LAYER_protocol common)         # wire formats: layouts, codes, SII parse
set(LAYER_twinsync_parameters common)     # the TWINsync parameter numbers alone (header-only)
set(LAYER_twinsync common twinsync_parameters)  # TWINsync telegram, mapping, link: pure
set(LAYER_device common protocol twinsync_parameters)  # device descriptions (the dictionary content)
set(LAYER_esc protocol device)     # the emulated ESC, the slave, the segment
set(LAYER_coe esc device)          # object dictionary, SDO server, PDO mapping
set(LAYER_foe esc)                 # FoE server, its files, the bootloader of the BOOT state
set(LAYER_eoe esc net)             # EoE server, the device's IP responder, its TAP interface
set(LAYER_soe esc drive_core)      # SoE server, the IDN model, the SoE drive (an application on the drive core)
set(LAYER_motion protocol)         # profile generator, mechanics, homing, CiA 402 state machine, touch probe
set(LAYER_drive_core motion twinsync)  # the drive core, its operation modes, the TWINsync coupling: no EtherCAT
set(LAYER_cia402 drive_core coe twinsync)  # the CoE adapter of the drive core, the TWINsync port
set(LAYER_net common)              # transport: raw socket, link, pcapng, netns, realtime, privileges
set(LAYER_serve net esc)           # serve loop, in-process link: a segment behind a link
set(LAYER_master protocol net)     # the master: wire formats and a link, never the slave emulation
set(LAYER_faults esc coe net)
set(LAYER_io esc faults)           # I/O terminals with behaviour: signals, wires, inputs forced by set_input
set(LAYER_report esc net network)  # the report on the master: checks on the frames beside the slaves, the
                                   # master against an ENI's InitCmds
set(LAYER_telemetry cia402 io telemetry_idl)  # io: the I/O terminals' channels (IoSample)
set(LAYER_telemetry_idl "")    # the telemetry IDL types compiled by idlc (with VECAT_TELEMETRY)
set(LAYER_telemetry_types "")  # ... and idlc's generated sources
set(LAYER_testing master cia402 faults telemetry serve)
set(LAYER_esi device esc)
set(LAYER_network cia402 esi io soe)   # networks of mixed devices from a file
set(LAYER_replay network esc)     # replay of real captures against a line built from a file or the capture
set(LAYER_clone master network)    # vecat clone: a line read with the master, written as a network file
set(LAYER_cli master telemetry cia402 faults esi serve esc report network replay foe eoe soe clone io)

# ---------------------------------------------------------------------------------------------------------
if(NOT SOURCE_DIR OR NOT LINKS)
  message(FATAL_ERROR "usage: cmake -DSOURCE_DIR=<tree> -DLINKS=<links.cmake> -P check_layering.cmake")
endif()
include(${LINKS})

set(_problems "")
macro(problem text)
  list(APPEND _problems "${text}")
endmacro()

# Everything lib may use, down the arrows of the table (LAYER_) or of CMake (LINKS_).
function(closure prefix lib out)
  set(_seen "")
  set(_todo ${${prefix}${lib}})
  while(_todo)
    list(POP_FRONT _todo _d)
    if(NOT _d IN_LIST _seen)
      list(APPEND _seen ${_d})
      list(APPEND _todo ${${prefix}${_d}})
    endif()
  endwhile()
  set(${out} "${_seen}" PARENT_SCOPE)
endfunction()

# ---- 1. The table against CMake.
foreach(lib IN LISTS CMAKE_LIBRARIES)
  if(NOT DEFINED LAYER_${lib})
    problem("library ${lib} (${FOLDER_${lib}}) is not in the table of cmake/check_layering.cmake")
    continue()
  endif()
  closure(LAYER_ ${lib} _allowed)
  closure(LINKS_ ${lib} _linked)
  foreach(d IN LISTS LAYER_${lib})
    if(NOT d IN_LIST _linked)
      problem("the table lets ${lib} use ${d}, but CMake does not link ${d} to ${lib}")
    endif()
  endforeach()
  foreach(d IN LISTS LINKS_${lib})
    if(NOT d IN_LIST _allowed)
      problem("CMake links ${lib} to ${d}, which the table does not allow")
    endif()
  endforeach()
endforeach()

# ---- 2. Every include of src/ and esi/ against the table.
# The library a file belongs to: the one with a source of the same stem in its folder, else the library
# named after the folder.
function(owner file out)
  get_filename_component(_dir ${file} DIRECTORY)
  get_filename_component(_stem ${file} NAME_WE)
  get_filename_component(_folder ${_dir} NAME)
  set(_owner "")
  foreach(lib IN LISTS CMAKE_LIBRARIES)
    if(FOLDER_${lib} STREQUAL _dir)
      foreach(s IN LISTS SOURCES_${lib})
        get_filename_component(_s ${s} NAME_WE)
        if(_s STREQUAL _stem)
          set(_owner ${lib})
        endif()
      endforeach()
    endif()
  endforeach()
  if(NOT _owner)
    if(_folder STREQUAL "cli")
      set(_owner cli)
    elseif(DEFINED FOLDER_${_folder} AND FOLDER_${_folder} STREQUAL _dir)
      set(_owner ${_folder})
    endif()
  endif()
  set(${out} "${_owner}" PARENT_SCOPE)
endfunction()

file(GLOB_RECURSE _files RELATIVE ${SOURCE_DIR} ${SOURCE_DIR}/src/*.hpp ${SOURCE_DIR}/src/*.cpp
     ${SOURCE_DIR}/esi/*.hpp ${SOURCE_DIR}/esi/*.cpp)
list(SORT _files)
set(_checked 0)
foreach(file IN LISTS _files)
  owner(${file} _mine)
  if(NOT _mine)
    problem("${file}: belongs to no library of the table")
    continue()
  endif()
  closure(LAYER_ ${_mine} _allowed)
  file(STRINGS ${SOURCE_DIR}/${file} _includes REGEX "^[ \t]*#[ \t]*include[ \t]*\"[a-z0-9_]+/")
  if(INJECT MATCHES "^${file}=(.*)$")
    list(APPEND _includes "#include \"${CMAKE_MATCH_1}\"")
  endif()
  foreach(inc IN LISTS _includes)
    string(REGEX REPLACE "^[ \t]*#[ \t]*include[ \t]*\"([^\"]+)\".*$" "\\1" _path "${inc}")
    string(REGEX MATCH "^[a-z0-9_]+" _folder "${_path}")
    if(_folder STREQUAL "esi")
      set(_target ${_path})
    elseif(IS_DIRECTORY ${SOURCE_DIR}/src/${_folder})
      set(_target src/${_path})
    else()
      continue()  # not a folder of the project (a generated or third-party header)
    endif()
    math(EXPR _checked "${_checked} + 1")
    owner(${_target} _theirs)
    if(NOT _theirs)
      problem("${file}: includes ${_path}, which belongs to no library of the table")
    elseif(NOT _theirs STREQUAL _mine AND NOT _theirs IN_LIST _allowed)
      problem("${file}: ${_mine} may not use ${_theirs} (includes ${_path})")
    endif()
  endforeach()
endforeach()

if(_problems)
  list(JOIN _problems "\n  " _text)
  message(FATAL_ERROR "folder dependency rule broken (the table: cmake/check_layering.cmake):\n  ${_text}")
endif()
message(STATUS "folder dependency rule holds: ${_checked} includes between folders checked")
