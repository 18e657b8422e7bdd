# tests/tools/gltf_check.mk - the independent glTF reader check (host-only C++ tool, never shipped).
#
#   make gltf-check-tool        builds $(BUILD_ROOT)/tools/gltf_check
#   make gltf-check             checks $(GLTF_CHECK_FILE), by default the cube.glb that the
#                               unit test test_out writes (run it first); GLTF_CHECK_FILE=x.glb for another
#   make -f tests/tools/gltf_check.mk gltf-check-tool    the same, without the main Makefile
#
# Included from the top-level Makefile (-include tests/tools/gltf_check.mk); every
# variable here is prefixed GLTF_CHECK_ so nothing leaks into the C build, and no
# target here is a default goal.  Always built with the host g++, whatever
# CROSS_COMPILE or PROFILE say.
#
# Needs the Debian packages libtinygltf-dev (/usr/include/tiny_gltf.h) and
# nlohmann-json3-dev (tiny_gltf.h includes <nlohmann/json.hpp>; libtinygltf-dev
# does not depend on it).  Header-only: nothing to link.

BUILD_ROOT ?= build
Q ?= @

GLTF_CHECK_DIR := $(patsubst %/,%,$(dir $(lastword $(MAKEFILE_LIST))))
GLTF_CHECK_CXX ?= g++
GLTF_CHECK_CXXFLAGS ?= -O2 -g
GLTF_CHECK_INC ?= /usr/include
GLTF_CHECK_FLAGS := -std=c++17 -Wall -Wextra -Wshadow -Werror
GLTF_CHECK_BIN := $(BUILD_ROOT)/tools/gltf_check
GLTF_CHECK_SRC := $(GLTF_CHECK_DIR)/gltf_check.cpp
GLTF_CHECK_FILE ?= $(BUILD_ROOT)/test_out/cube.glb

.PHONY: gltf-check-tool gltf-check

gltf-check-tool: $(GLTF_CHECK_BIN)

$(GLTF_CHECK_BIN): $(GLTF_CHECK_SRC) $(GLTF_CHECK_DIR)/gltf_check.mk
	@test -f $(GLTF_CHECK_INC)/tiny_gltf.h && test -f $(GLTF_CHECK_INC)/nlohmann/json.hpp || { \
	  echo "gltf_check: tiny_gltf.h or nlohmann/json.hpp not found in $(GLTF_CHECK_INC); install them with:" >&2; \
	  echo "  apt-get install libtinygltf-dev nlohmann-json3-dev" >&2; \
	  exit 1; }
	@mkdir -p $(@D)
	@echo "  CXX     $@"
	$(Q)$(GLTF_CHECK_CXX) $(GLTF_CHECK_FLAGS) $(GLTF_CHECK_CXXFLAGS) -o $@ $<

gltf-check: $(GLTF_CHECK_BIN)
	@test -f $(GLTF_CHECK_FILE) || { echo "gltf_check: $(GLTF_CHECK_FILE) not found (the unit test test_out writes it)" >&2; exit 1; }
	$(Q)$(GLTF_CHECK_BIN) $(GLTF_CHECK_FILE)
