# qnav_object_copy(TARGET NAME): an OBJECT library NAME made from TARGET's own sources,
# compiled with its include folders and definitions (those of its dependencies too): the
# same code built another way beside it, e.g. qnavpy's copies without the sanitizers
# (python/) or the benchmarks' copies that count network evaluations (bench/).
include_guard(GLOBAL)

function(qnav_object_copy target name)
  get_target_property(srcs ${target} SOURCES)
  get_target_property(dir ${target} SOURCE_DIR)
  list(TRANSFORM srcs PREPEND ${dir}/)
  add_library(${name} OBJECT ${srcs})
  target_include_directories(${name} PRIVATE $<TARGET_PROPERTY:${target},INCLUDE_DIRECTORIES>)
  target_compile_definitions(${name} PRIVATE $<TARGET_PROPERTY:${target},COMPILE_DEFINITIONS>)
  set_target_properties(${name} PROPERTIES C_STANDARD 99 C_EXTENSIONS OFF)
endfunction()
