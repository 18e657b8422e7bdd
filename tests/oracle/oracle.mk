# tests/oracle/oracle.mk - the OCCT test oracle (host-only C++ tool, never shipped).
#
#   make oracle                 builds $(BUILD_ROOT)/tools/occt_oracle
#   make oracle-selftest        sample -> points round trip on one model (ORACLE_MODEL)
#   make -f tests/oracle/oracle.mk oracle      the same, without the main Makefile
#
# Included from the top-level Makefile (-include tests/oracle/oracle.mk); every
# variable here is prefixed ORACLE_ so nothing leaks into the C build, and no target
# here is a default goal.  The oracle is a workstation tool: it is always built with
# the host g++, whatever CROSS_COMPILE or PROFILE say.
#
# Needs the Debian packages libocct-data-exchange-dev, libocct-modeling-algorithms-dev,
# libocct-modeling-data-dev and libocct-foundation-dev (OCCT 7.6 on Debian 12).

BUILD_ROOT ?= build

# directory of this fragment, taken before any other makefile is read
ORACLE_DIR := $(patsubst %/,%,$(dir $(lastword $(MAKEFILE_LIST))))

ORACLE_CXX ?= g++
ORACLE_OCCT_INC ?= /usr/include/opencascade
ORACLE_OCCT_LIBDIR ?=
ORACLE_CXXFLAGS ?= -O2 -g
# -isystem: warnings are for our code, not for OCCT's headers
ORACLE_FLAGS := -std=c++17 -Wall -Wextra -Wshadow -Werror -isystem $(ORACLE_OCCT_INC)
# Link order: users before providers.  TKIGES reads IGES; TKSTEP (with TKSTEP209,
# TKSTEPAttr and TKSTEPBase, the AP209/attribute/base entity schemas it needs) reads
# STEP; TKXSBase is the data-exchange core both sit on; TKShHealing heals the result
# on the way in, TKMesh tessellates, TKTopAlgo has sewing, face classification and
# BRepExtrema, TKGeomAlgo curve projection, the rest is the geometry/topology core.
ORACLE_LIBS := -lTKIGES -lTKSTEP -lTKSTEP209 -lTKSTEPAttr -lTKSTEPBase -lTKXSBase -lTKMesh \
               -lTKShHealing -lTKTopAlgo -lTKGeomAlgo -lTKBRep -lTKGeomBase -lTKG3d -lTKG2d \
               -lTKMath -lTKernel
ORACLE_LDFLAGS := $(if $(ORACLE_OCCT_LIBDIR),-L$(ORACLE_OCCT_LIBDIR))

ORACLE_BIN := $(BUILD_ROOT)/tools/occt_oracle
ORACLE_SRC := $(ORACLE_DIR)/occt_oracle.cpp
ORACLE_MODEL ?= ../shared/models/iges/elif__brick_with_hole.IGS

.PHONY: oracle oracle-selftest oracle-clean

oracle: $(ORACLE_BIN)

$(ORACLE_BIN): $(ORACLE_SRC) $(ORACLE_DIR)/oracle.mk
	@test -f $(ORACLE_OCCT_INC)/IGESControl_Reader.hxx || { \
	  echo "oracle: OCCT headers not found in $(ORACLE_OCCT_INC); install them with:" >&2; \
	  echo "  apt-get install libocct-data-exchange-dev libocct-modeling-algorithms-dev libocct-modeling-data-dev libocct-foundation-dev" >&2; \
	  exit 1; }
	@mkdir -p $(@D)
	@echo "  CXX     $@"
	$(Q)$(ORACLE_CXX) $(ORACLE_FLAGS) $(ORACLE_CXXFLAGS) -o $@ $< $(ORACLE_LDFLAGS) $(ORACLE_LIBS)

# Self-consistency: points sampled on the faces by OCCT must be ~0 from the faces.
oracle-selftest: $(ORACLE_BIN)
	@mkdir -p $(BUILD_ROOT)/oracle
	$(Q)$(ORACLE_BIN) info $(ORACLE_MODEL)
	$(Q)$(ORACLE_BIN) sample $(ORACLE_MODEL) $(BUILD_ROOT)/oracle/selftest.xyz --per-face 50 >/dev/null
	$(Q)$(ORACLE_BIN) points $(ORACLE_MODEL) $(BUILD_ROOT)/oracle/selftest.xyz --tol-rel 1e-9

oracle-clean:
	rm -f $(ORACLE_BIN)
	rm -rf $(BUILD_ROOT)/oracle
