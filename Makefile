# curvemesh - one non-recursive Makefile.
#
#   make [all]            library, tools and terminal binaries for PROFILE
#   make check            installs missing Debian packages (deps), then every test and gate
#   make demo             encode a bundled model and decode it as the terminal does (out/demo.glb)
#   make test             the fast tier (under 2 minutes warm)
#   make print-limits     the compile-time limits of PROFILE
#   make CROSS_COMPILE=aarch64-linux-gnu-    cross build (arm-linux-gnueabihf- too)
#   make install PREFIX=/usr DESTDIR=/tmp/stage
#   V=1 shows the commands.
#
# Comments stay on their own lines: in GNU make `VAR ?= x  # note` keeps the
# spaces before '#' in the value.

.DEFAULT_GOAL := all
.DELETE_ON_ERROR:
.SUFFIXES:
SHELL := /bin/bash

# ---- toolchain (cross-friendly: CC from the environment wins, CROSS_COMPILE prefixes the defaults) ----
CROSS_COMPILE ?=
ifeq ($(origin CC),default)
CC := $(CROSS_COMPILE)gcc
endif
ifeq ($(origin AR),default)
AR := $(CROSS_COMPILE)ar
endif
NM ?= $(CROSS_COMPILE)nm
PKG_CONFIG ?= $(CROSS_COMPILE)pkg-config
# tools that run on the build machine during the build (stack checker)
HOSTCC ?= cc

# board profile: fixedcfg/profiles/$(PROFILE).h
PROFILE ?= terminal
PROFILES := terminal host tiny
ifeq ($(filter $(PROFILE),$(PROFILES)),)
$(error PROFILE=$(PROFILE) is not one of: $(PROFILES))
endif

TRIPLET := $(shell $(CC) -dumpmachine 2>/dev/null)
ifeq ($(TRIPLET),)
$(error cannot run '$(CC) -dumpmachine': is the compiler installed? (make deps))
endif
CC_IS_CLANG := $(shell $(CC) --version 2>/dev/null | grep -qi clang && echo 1)
BUILD_ROOT ?= build
# objects of one (architecture, profile) pair
bdir = $(BUILD_ROOT)/$(TRIPLET)-$(1)
B := $(call bdir,$(PROFILE))

# ---- install (GNU conventions; DESTDIR is never set here) ----
PREFIX ?= /usr/local
BINDIR ?= $(PREFIX)/bin

V ?= 0
ifeq ($(V),1)
Q :=
else
Q := @
endif
# "  CC      file" progress lines, silenced by make -s
ifneq ($(findstring s,$(firstword -$(MAKEFLAGS))),)
say :=
else
say = @echo "  $(1)$(2)"
endif

# ---- flags: the project's own, kept apart from the user's CFLAGS/CPPFLAGS/LDFLAGS ----
CFLAGS ?= -O2 -g
# binary64 everywhere, no FMA contraction: x86-64 and ARM rebuild bit-identical surfaces
CM_STD := -std=c11 -ffp-contract=off -fno-fast-math
ifneq ($(filter i386-% i486-% i586-% i686-%,$(TRIPLET)),)
CM_STD += -msse2 -mfpmath=sse
endif
# code size of the board's programs (issue 15: aarch64 text within CM_PROGRAM_TEXT_BUDGET, make
# check-ram): no unwind tables (C throws nothing; gdb reads -g's .debug_frame) and each function
# and object in its own section, so that the link drops what a program never calls (CM_GC_SECTIONS:
# the decoder library holds the writer's packers, the host tools' helpers).  aarch64 cmz-terminal:
# 302 650 -> 256 057 bytes of text and read-only data.  Not under the sanitizers, whose reports
# unwind through the tables.
ifeq ($(findstring -fsanitize,$(CFLAGS)),)
CM_STD += -fno-asynchronous-unwind-tables -fno-unwind-tables -ffunction-sections -fdata-sections
CM_GC_SECTIONS := -Wl,--gc-sections
# aarch64: Cortex-A53 erratum 843419 fixed by rewriting the affected ADRP as ADR (the linker fails,
# loudly, where an ADR cannot reach), not by ld's default veneers, whose section it aligns to 4 KiB:
# one veneer cost cmz-terminal 4 096 bytes of text in a layout where a function's ADRP fell on a
# page's last words (a Raspberry Pi 3's core has the erratum: the fix stays on)
ifneq ($(filter aarch64-%,$(TRIPLET)),)
CM_GC_SECTIONS += -Wl,--fix-cortex-a53-843419=adr
endif
# platform/ (the link, the store, the transports, the programs' mains: I/O, no numerics) is
# compiled for size: 8.6 KB less aarch64 code, which made room for issue 15's streaming (cmz-terminal
# 262 122 bytes at -O2, over the budget with the first review fix).  Appended after CFLAGS: it wins.
CM_PLATFORM_OPT := -Os
# and so is the decoder's code that runs once per file or per face, never per vertex: the file parser
# and its tables, limits and messages, the face methods' records (their kernels stay -O2), the
# number formatting of the text outputs (with
# -ffp-contract=off every sum rounds alike at any -O): 7.3 KB of cmz-terminal's aarch64 text (the parser
# 5.1, the rest 2.2), room in the budget for the evaluator's per-degree fast paths; the methods
# 0.9 KB more, room for cmz-terminal --display; the range decoder (the file's symbols, a few
# thousand per model) 0.9 KB more, room for format 4.9's kept-face plane (cmz-terminal 262 566 ->
# 261 670 bytes); a GREGORY face's corner normals and the choice of its edges' cubics (cm_corner.c,
# once per face: the K7 fits themselves stay -O2), room for format 4.10's patch scale (262 214 ->
# 261 526 bytes; +0.1 to +0.3 % terminal instructions on Tightening_screw, asmo, C1G0B0O); cmz-view's
# glTF reader (cm_glb_read.c, once per file: cmz-view 229 436 -> 243 980 bytes, 245 788 at -O2); the
# GLB writer (cm_glb.c: its loops are copies), room for cmz-terminal's serving viewer on a DRM
# display (263 060 -> 261 812 bytes; C1G0B0O's decode 647.13 -> 646.96 M instructions); the output's
# checks (cm_out.c, once per file: their reads a run at a time made them 1.1 KB larger and 2 to 4 %
# of a decode cheaper; -Os took 0.7 KB of it back at no cost in instructions); the exact patches'
# construction (cm_egregface.c: its sides and corners once per face; the patches' evaluation,
# cm_egreg.c, stays -O2), room for format 4.13's corner hints (cmz-terminal 262 926 -> 261 694 bytes)
CM_COLD_SRC := decoder/src/cm_decode.c decoder/src/cm_format.c decoder/src/cm_sections.c decoder/src/cm_limits.c \
               decoder/src/cm_error.c decoder/src/cm_arith.c decoder/out/cm_numfmt.c decoder/out/cm_obj.c decoder/out/cm_stl.c \
               decoder/src/cm_corner.c decoder/view/cm_glb_read.c decoder/out/cm_glb.c decoder/out/cm_out.c \
               decoder/kernels/cm_egregface.c \
               $(wildcard decoder/methods/*.c)
# and the viewer's drawing, run per triangle and pixel of every frame, its loops peeled and
# unswitched (gcc; clang has no such flags): issue 17's frame of 100 k triangles 2 to 3 % fewer
# instructions (tail_section 52.9 -> 51.5 M, asmo 59.2 -> 58.0 M), the same pixels, for 1 KB of
# x86-64 text (-O3: 4.6 KB, a further 1 %)
CM_HOT_SRC := decoder/view/cm_view.c
CM_HOT_OPT := $(if $(CC_IS_CLANG),,-fpeel-loops -funswitch-loops)
endif
CM_WARN := -Wall -Wextra -Wundef -Wshadow -Wstrict-prototypes -Wmissing-prototypes -Wcast-align \
           -Wformat=2 -Wvla -Walloca -Wdouble-promotion -Werror
# the heap-free decoder and kernels also refuse silent narrowing
CM_WARN_DECODER := $(CM_WARN) -Wconversion
# stack: per-function budget at compile time (the profile's CM_STACK_FN_MAX),
# call graph for check-stack (gcc only; clang gets the frame-size warning)
limit_of = $(shell echo $(2) | $(CC) -E -P -Ifixedcfg -DCM_PROFILE='"profiles/$(1).h"' -include cm_limits.h - \
	2>/dev/null | tail -n 1)
ifeq ($(CC_IS_CLANG),1)
stack_flags = -Wframe-larger-than=$(call limit_of,$(1),CM_STACK_FN_MAX)
else
stack_flags = -fstack-usage -fcallgraph-info=su -Wstack-usage=$(call limit_of,$(1),CM_STACK_FN_MAX)
endif
ifeq ($(CM_NO_STACK_FLAGS),1)
stack_flags =
endif
# the decoder sees only fixedcfg and its own headers; everything else may also use platform/
CM_INC := -Ifixedcfg -Idecoder/include -Idecoder/src
CM_INC_ALL := $(CM_INC) -Iplatform -Ihost_tools
DEPFLAGS = -MMD -MP
CMOCKA_CFLAGS = $(shell $(PKG_CONFIG) --cflags cmocka 2>/dev/null)
CMOCKA_LIBS = $(shell $(PKG_CONFIG) --libs cmocka 2>/dev/null || echo -lcmocka)
# the terminal's programs and the unit tests abort on any heap call made by project code: linked with
# these flags and platform/cm_noheap_wrap.c (a security property of the terminal; check-noheap, layer b)
NOHEAP_WRAP := -Wl,--wrap=malloc,--wrap=calloc,--wrap=realloc,--wrap=free,--wrap=aligned_alloc,--wrap=posix_memalign

# ---- sources ----
KERNEL_SRC := $(sort $(wildcard decoder/kernels/*.c))
DECODER_SRC := $(sort $(wildcard decoder/src/*.c decoder/methods/*.c))
OUT_SRC := $(sort $(wildcard decoder/out/*.c))
VIEW_SRC := $(sort $(wildcard decoder/view/*.c))
LIB_SRC := $(KERNEL_SRC) $(DECODER_SRC) $(OUT_SRC) $(VIEW_SRC)
UNIT_SRC := $(sort $(wildcard tests/unit/test_*.c))
UNIT_NAMES := $(patsubst tests/unit/%.c,%,$(UNIT_SRC))
# workstation code: everything under host_tools/ except the program mains (*_main.c)
HOST_SRC := $(sort $(filter-out %_main.c %profile_table.c,$(wildcard host_tools/*.c host_tools/*/*.c)))
HOST_TEST_SRC := $(sort $(wildcard tests/host/test_*.c))
HOST_TEST_NAMES := $(patsubst tests/host/%.c,%,$(HOST_TEST_SRC))
# helpers linked into every host test (synthetic IGES writer, ...)
HOST_TEST_HELPERS := $(sort $(filter-out tests/host/test_%.c,$(wildcard tests/host/*.c)))

# ---- per-profile rules: objects, library, unit tests ----
# $(1) = profile.  Objects of decoder/ get the strict warnings and the stack flags.
define PROFILE_RULES
STACK_FLAGS_$(1) := $(call stack_flags,$(1))
# the host profile's decoder state is over 3 GB of bss: on x86-64 its large arrays go to .lbss,
# beyond the 2 GB that the small code model reaches (objects under 64 KiB stay near the code)
MODEL_FLAGS_$(1) := $(if $(and $(filter host,$(1)),$(filter x86_64-%,$(TRIPLET))),-mcmodel=medium)
$(call bdir,$(1))/decoder/%.o: decoder/%.c
	@mkdir -p $$(@D)
	$$(call say,CC      ,$$@)
	$$(Q)$$(CC) $$(CM_INC) -DCM_PROFILE='"profiles/$(1).h"' $$(CPPFLAGS) $$(CM_STD) $$(CM_WARN_DECODER) \
		$$(STACK_FLAGS_$(1)) $$(MODEL_FLAGS_$(1)) $$(CFLAGS) $$(if $$(filter $$(CM_COLD_SRC),$$<),$$(CM_PLATFORM_OPT)) \
		$$(if $$(filter $$(CM_HOT_SRC),$$<),$$(CM_HOT_OPT)) $$(DEPFLAGS) -c $$< -o $$@

$(call bdir,$(1))/%.o: %.c
	@mkdir -p $$(@D)
	$$(call say,CC      ,$$@)
	$$(Q)$$(CC) $$(CM_INC_ALL) -DCM_PROFILE='"profiles/$(1).h"' -DCM_EXPECT_PROFILE='"$(1)"' $$(CPPFLAGS) \
		$$(CM_STD) $$(CM_WARN) $$(MODEL_FLAGS_$(1)) $$(CMOCKA_CFLAGS) $$(CFLAGS) \
		$$(if $$(filter platform/%,$$<),$$(CM_PLATFORM_OPT)) $$(DEPFLAGS) -c $$< -o $$@

$(call bdir,$(1))/libcmdecoder.a: $(patsubst %.c,$(call bdir,$(1))/%.o,$(LIB_SRC))
	$$(call say,AR      ,$$@)
	$$(Q)rm -f $$@ && $$(AR) rcs $$@ $$^

$(addprefix $(call bdir,$(1))/tests/unit/,$(UNIT_NAMES)): $(call bdir,$(1))/tests/unit/%: $(call bdir,$(1))/tests/unit/%.o $(call bdir,$(1))/platform/cm_noheap_wrap.o \
		$(call bdir,$(1))/platform/cm_report.o $(call bdir,$(1))/libcmdecoder.a
	$$(call say,LD      ,$$@)
	$$(Q)$$(CC) $$(CFLAGS) $$(LDFLAGS) $$(NOHEAP_WRAP) -o $$@ $$^ $$(CMOCKA_LIBS) -lm

$(call bdir,$(1))/tests/unit/kernel_vectors: $(call bdir,$(1))/tests/unit/kernel_vectors.o $(call bdir,$(1))/libcmdecoder.a
	$$(call say,LD      ,$$@)
	$$(Q)$$(CC) $$(CFLAGS) $$(LDFLAGS) -o $$@ $$^ -lm

$(call bdir,$(1))/cm-limits: $(call bdir,$(1))/platform/cm_report.o $(call bdir,$(1))/platform/cm_limits_main.o \
		$(call bdir,$(1))/libcmdecoder.a
	$$(call say,LD      ,$$@)
	$$(Q)$$(CC) $$(CFLAGS) $$(LDFLAGS) -o $$@ $$^ -lm

# the framebuffer output's pixel work, on plain memory (platform code: the one unit test that links it)
$(call bdir,$(1))/tests/unit/test_fb: $(call bdir,$(1))/platform/cm_fb.o

unit-tests-$(1): $(addprefix $(call bdir,$(1))/tests/unit/,$(UNIT_NAMES) kernel_vectors)

# the terminal's decoder, built with this profile; no heap on its path (linked with the abort wrappers)
$(call bdir,$(1))/cmz-decode: $(call bdir,$(1))/platform/cmz_decode_main.o $(call bdir,$(1))/platform/cm_decode_file.o \
		$(call bdir,$(1))/platform/cm_report.o $(call bdir,$(1))/platform/cm_noheap_wrap.o $(call bdir,$(1))/libcmdecoder.a
	$$(call say,LD      ,$$@)
	$$(Q)$$(CC) $$(CFLAGS) $$(LDFLAGS) $$(CM_GC_SECTIONS) $$(NOHEAP_WRAP) -o $$@ $$^ -lm

# what the terminal shows, as a PNG (issue 17): the decoder and the software viewer, no heap either
$(call bdir,$(1))/cmz-view: $(call bdir,$(1))/platform/cmz_view_main.o $(call bdir,$(1))/platform/cm_decode_file.o \
		$(call bdir,$(1))/platform/cm_fb.o \
		$(call bdir,$(1))/platform/cm_report.o $(call bdir,$(1))/platform/cm_noheap_wrap.o $(call bdir,$(1))/libcmdecoder.a
	$$(call say,LD      ,$$@)
	$$(Q)$$(CC) $$(CFLAGS) $$(LDFLAGS) $$(CM_GC_SECTIONS) $$(NOHEAP_WRAP) -o $$@ $$^ $$(GPIO_LIBS) -lm

$(call bdir,$(1))/libcmhost.a: $(patsubst %.c,$(call bdir,$(1))/%.o,$(HOST_SRC) platform/cm_report.c)
	$$(call say,AR      ,$$@)
	$$(Q)rm -f $$@ && $$(AR) rcs $$@ $$^

$(addprefix $(call bdir,$(1))/tests/host/,$(HOST_TEST_NAMES)): $(call bdir,$(1))/tests/host/%: \
		$(call bdir,$(1))/tests/host/%.o $(patsubst %.c,$(call bdir,$(1))/%.o,$(HOST_TEST_HELPERS)) \
		$(call bdir,$(1))/libcmhost.a $(call bdir,$(1))/libcmdecoder.a
	$$(call say,LD      ,$$@)
	$$(Q)$$(CC) $$(CFLAGS) $$(LDFLAGS) -o $$@ $$^ $$(CMOCKA_LIBS) -lm

host-tests-$(1): $(addprefix $(call bdir,$(1))/tests/host/,$(HOST_TEST_NAMES))

# fuzz targets replayed without libFuzzer (tests/fuzz/replay_main.c); the decoder's needs no host code
$(call bdir,$(1))/tests/fuzz/replay_decode: $(call bdir,$(1))/tests/fuzz/fuzz_decode.o $(call bdir,$(1))/tests/fuzz/replay_main.o \
		$(call bdir,$(1))/libcmdecoder.a
	$$(call say,LD      ,$$@)
	$$(Q)$$(CC) $$(CFLAGS) $$(LDFLAGS) -o $$@ $$^ -lm
# the triangulator's: no host code either
$(call bdir,$(1))/tests/fuzz/replay_tess: $(call bdir,$(1))/tests/fuzz/fuzz_tess.o $(call bdir,$(1))/tests/fuzz/replay_main.o \
		$(call bdir,$(1))/libcmdecoder.a
	$$(call say,LD      ,$$@)
	$$(Q)$$(CC) $$(CFLAGS) $$(LDFLAGS) -o $$@ $$^ -lm
# the viewer's glTF input's: no host code either
$(call bdir,$(1))/tests/fuzz/replay_glb: $(call bdir,$(1))/tests/fuzz/fuzz_glb.o $(call bdir,$(1))/tests/fuzz/replay_main.o \
		$(call bdir,$(1))/libcmdecoder.a
	$$(call say,LD      ,$$@)
	$$(Q)$$(CC) $$(CFLAGS) $$(LDFLAGS) -o $$@ $$^ -lm
$(call bdir,$(1))/tests/fuzz/replay_%: $(call bdir,$(1))/tests/fuzz/fuzz_%.o $(call bdir,$(1))/tests/fuzz/replay_main.o \
		$(call bdir,$(1))/libcmhost.a $(call bdir,$(1))/libcmdecoder.a
	$$(call say,LD      ,$$@)
	$$(Q)$$(CC) $$(CFLAGS) $$(LDFLAGS) -o $$@ $$^ -lm
endef
$(foreach p,$(PROFILES),$(eval $(call PROFILE_RULES,$(p))))
LIMIT_TOOLS := $(foreach p,$(PROFILES),$(call bdir,$(p))/cm-limits)

# every profile's limits table, for `cmz encode --profile NAME`
PROFILE_TABLES := $(foreach p,$(PROFILES),$(call bdir,host)/host_tools/profile_table_$(p).o)
# (the limits' headers named: a changed default must reach `cmz encode --profile`; and its other
# headers tracked like every object's: cm_limit_info's rows changed, an old object would be read
# with the new layout)
$(call bdir,host)/host_tools/profile_table_%.o: host_tools/profile_table.c fixedcfg/cm_limits.h \
		fixedcfg/cm_limits_list.h fixedcfg/profiles/%.h
	@mkdir -p $(@D)
	$(call say,CC      ,$@)
	$(Q)$(CC) $(CM_INC_ALL) -DCM_PROFILE='"profiles/$*.h"' -DPROFILE_TABLE=cm_profile_table_$* $(CPPFLAGS) \
		$(CM_STD) $(CM_WARN) $(CFLAGS) $(DEPFLAGS) -c $< -o $@

# test tool: the decoded mesh's topology (host profile)
# a .cmz header's needs read or rewritten, any format (the lying-header and bundled round-trip gates);
# defined before the rules that name it as a prerequisite (make expands those when it reads them)
CMZ_HEADER := $(call bdir,host)/tests/tools/cmz_header
$(CMZ_HEADER): $(call bdir,host)/tests/tools/cmz_header.o $(call bdir,host)/libcmdecoder.a
	$(call say,LD      ,$@)
	$(Q)$(CC) $(CFLAGS) $(LDFLAGS) -o $@ $^ -lm
# benchmark tool: the best wall time of a command, or of two in turns (bench.sh, bench_peers.sh)
WALL_MIN := $(call bdir,host)/tests/tools/wall_min
$(WALL_MIN): $(call bdir,host)/tests/tools/wall_min.o
	$(call say,LD      ,$@)
	$(Q)$(CC) $(CFLAGS) $(LDFLAGS) -o $@ $^
MESH_CHECK := $(call bdir,host)/tests/tools/mesh_check
$(MESH_CHECK): $(call bdir,host)/tests/tools/mesh_check.o $(call bdir,host)/host_tools/mesh/mesh_topo.o \
		$(call bdir,host)/platform/cm_decode_file.o $(call bdir,host)/platform/cm_report.o $(call bdir,host)/libcmdecoder.a
	$(call say,LD      ,$@)
	$(Q)$(CC) $(CFLAGS) $(LDFLAGS) -o $@ $^ -lm

# the workstation tool, always built with the host profile
CMZ := $(call bdir,host)/cmz
# the link and the board's devices (platform/ back ends, cmz-terminal, cmz send, VM tests): one
# fragment per concern
include $(sort $(wildcard mk/*.mk))
# (mk/terminal.mk adds the link protocol and the transports for `cmz send`)
$(CMZ): $(call bdir,host)/host_tools/cmz_main.o $(PROFILE_TABLES) $(CMZ_EXTRA_OBJS) $(call bdir,host)/libcmhost.a \
		$(call bdir,host)/platform/cm_decode_file.o $(call bdir,host)/libcmdecoder.a
	$(call say,LD      ,$@)
	$(Q)$(CC) $(CFLAGS) $(LDFLAGS) -o $@ $^ $(CMZ_EXTRA_LIBS) -lm

.PRECIOUS: $(BUILD_ROOT)/%.o

# the Open CASCADE oracle (tests only): make oracle
-include tests/oracle/oracle.mk
# the glTF reader check (tests only): make gltf-check
-include tests/tools/gltf_check.mk
.PHONY: all lib unit-tests $(addprefix unit-tests-,$(PROFILES)) $(addprefix host-tests-,$(PROFILES))

all: lib $(B)/cm-limits $(B)/cmz-decode $(B)/cmz-view $(CMZ)
lib: $(B)/libcmdecoder.a
unit-tests: unit-tests-$(PROFILE)

-include $(shell find $(BUILD_ROOT) -name '*.d' 2>/dev/null)

# ---- limits ----
.PHONY: print-limits
print-limits: $(B)/cm-limits
	$(Q)$(B)/cm-limits

# ---- checks ----
# Each suite prints TAP-like "ok"/"not ok" lines; tests/tools/run_suites.sh
# runs them all and ends with "N passed, N failed".
STACK_CHECK := $(BUILD_ROOT)/tools/check_stack
$(STACK_CHECK): tests/tools/check_stack.c
	@mkdir -p $(@D)
	$(call say,HOSTCC  ,$@)
	$(Q)$(HOSTCC) -std=c11 -O2 -Wall -Wextra -Werror -o $@ $<

.PHONY: check check-run check-noheap check-stack check-cross check-clang check-fuzz-replay check-fuzz-decode-replay \
	check-corpus-roundtrip check-decode-cross check-view check-view-cross check-three check-corpus-occt check-step-occt check-step-roundtrip deps
# `make check` on a fresh machine: install what is missing, then test.
# The builds run on every core (CHECK_JOBS); the suites and gates still run one at a time, but their
# own builds (clang, cross, -O0) share the job slots.
CHECK_JOBS ?= $(shell nproc 2>/dev/null || echo 2)
check:
	$(Q)$(MAKE) --no-print-directory deps
	$(Q)$(MAKE) --no-print-directory -j$(CHECK_JOBS) check-run

CROSS_TARGETS := aarch64-linux-gnu- arm-linux-gnueabihf-

# what both tiers start with: the unit tests of every profile, the workstation tests, the no-heap gate,
# and that no face method is named outside its module
UNIT_SUITES = "unit-host:$(call bdir,host)/tests/unit" "unit-terminal:$(call bdir,terminal)/tests/unit" \
	"unit-tiny:$(call bdir,tiny)/tests/unit" "host:$(call bdir,host)/tests/host" \
	"gate:noheap:$(MAKE) --no-print-directory -s check-noheap" \
	"gate:method-modules:tests/tools/check_method_modules.sh"

check-run: $(foreach p,$(PROFILES),unit-tests-$(p)) host-tests-host $(call bdir,terminal)/libcmdecoder.a \
		$(LIMIT_TOOLS) $(STACK_CHECK)
	$(Q)tests/tools/run_suites.sh \
		$(UNIT_SUITES) \
		"gate:gates-reject-bad-code:tests/tools/gate_selftest.sh $(HOSTCC) nm $(STACK_CHECK) $(BUILD_ROOT)/gate-selftest" \
		"gate:readme-tables:$(MAKE) --no-print-directory -s check-readme" \
		"gate:stack:$(MAKE) --no-print-directory -s check-stack" \
		"gate:stack-aarch64:$(MAKE) --no-print-directory -s CROSS_COMPILE=aarch64-linux-gnu- check-stack" \
		"gate:stack-programs:$(MAKE) --no-print-directory -s check-stack-programs" \
		"gate:stack-programs-aarch64:$(MAKE) --no-print-directory -s CROSS_COMPILE=aarch64-linux-gnu- check-stack-programs" \
		"gate:ram:$(MAKE) --no-print-directory -s check-ram" \
		"gate:ram-aarch64:$(MAKE) --no-print-directory -s CROSS_COMPILE=aarch64-linux-gnu- check-ram" \
		"gate:clang-sanitizers:$(MAKE) --no-print-directory -s check-clang" \
		"gate:import-fuzz-replay:$(MAKE) --no-print-directory -s check-fuzz-replay" \
		"gate:decode-fuzz-replay:$(MAKE) --no-print-directory -s check-fuzz-decode-replay" \
		"gate:tess-fuzz-replay:$(MAKE) --no-print-directory -s check-fuzz-tess-replay" \
		"gate:glb-fuzz-replay:$(MAKE) --no-print-directory -s check-fuzz-glb-replay" \
		"gate:corpus-vs-occt:$(MAKE) --no-print-directory -s check-corpus-occt" \
		"gate:corpus-roundtrip:$(MAKE) --no-print-directory -s check-corpus-roundtrip" \
		"gate:step-vs-occt:$(MAKE) --no-print-directory -s check-step-occt" \
		"gate:step-roundtrip:$(MAKE) --no-print-directory -s check-step-roundtrip" \
		"gate:cross:$(MAKE) --no-print-directory -s check-cross" \
		"gate:decode-cross:$(MAKE) --no-print-directory -s check-decode-cross" \
		"gate:view-cross:$(MAKE) --no-print-directory -s check-view-cross" \
		"gate:view-vs-three.js:$(MAKE) --no-print-directory -s check-three" \
		"gate:usb-build:$(MAKE) --no-print-directory -s check-usb-build" \
		"gate:link-fuzz-replay:$(MAKE) --no-print-directory -s check-fuzz-link-replay" \
		"gate:leave-out:$(MAKE) --no-print-directory -s check-leave-out" \
		"gate:vault:$(MAKE) --no-print-directory -s check-vault" \
		"gate:encode-jobs:$(MAKE) --no-print-directory -s check-encode-jobs" \
		"gate:lying-header:$(MAKE) --no-print-directory -s check-lying-header" \
		"gate:old-files:$(MAKE) --no-print-directory -s check-old-files" \
		"gate:hostile-input:$(MAKE) --no-print-directory -s hostile HOSTILE_TRIES=2 HOSTILE_TAP=--tap" \
		"gate:store-kill:$(MAKE) --no-print-directory -s check-store-kill" \
		"gate:hw-and-links:$(MAKE) --no-print-directory -s check-hw-and-links"

# `make test`: the fast tier for the inner loop (under 2 minutes warm on 2 cores): unit tests of
# every profile, the workstation tests, the no-heap and stack gates (x86-64), the fuzz regression
# replays without the shared corpus, and a round trip of the bundled models.  `make check` stays
# the full gate (CI); nothing here is skipped there.
.PHONY: test check-fuzz-replay-fast check-bundled-roundtrip
test: $(foreach p,$(PROFILES),unit-tests-$(p)) host-tests-host $(call bdir,terminal)/libcmdecoder.a $(STACK_CHECK)
	$(Q)tests/tools/run_suites.sh \
		$(UNIT_SUITES) \
		"gate:stack:$(MAKE) --no-print-directory -s check-stack" \
		"gate:stack-programs:$(MAKE) --no-print-directory -s check-stack-programs" \
		"gate:ram:$(MAKE) --no-print-directory -s check-ram" \
		"gate:fuzz-replays:$(MAKE) --no-print-directory -s check-fuzz-replay-fast" \
		"gate:bundled-roundtrip:$(MAKE) --no-print-directory -s check-bundled-roundtrip" \
		"gate:vault:$(MAKE) --no-print-directory -s check-vault" \
		"gate:lying-header:$(MAKE) --no-print-directory -s check-lying-header" \
		"gate:old-files:$(MAKE) --no-print-directory -s check-old-files" \
		"gate:view:$(MAKE) --no-print-directory -s check-view"

# every fuzz target's seeds and regressions replayed under the sanitizers, the shared corpus left
# to check-fuzz-replay (2.5 minutes of 2-4 MB models under ASan)
check-fuzz-replay-fast:
	$(Q)$(MAKE) --no-print-directory -s check-fuzz-replay FUZZ_REPLAY_SHARED= FUZZ_REPLAY_SHARED_STEP=
	$(Q)$(MAKE) --no-print-directory -s check-fuzz-decode-replay
	$(Q)$(MAKE) --no-print-directory -s check-fuzz-tess-replay
	$(Q)$(MAKE) --no-print-directory -s check-fuzz-glb-replay
	$(Q)$(MAKE) --no-print-directory -s check-fuzz-link-replay

# headers declaring fewer triangles than the faces make: 60 % decodes whole (the host grows its mesh),
# 1 is refused by both decoders, naming MAX_TRIS and the header (issues 10, 11)
.PHONY: check-lying-header
check-lying-header: $(CMZ) $(call bdir,terminal)/cmz-decode $(CMZ_HEADER)
	$(Q)tests/tools/check_lying_header.sh $(CMZ) $(call bdir,terminal)/cmz-decode tests/data/geo_example.igs $(CMZ_HEADER)

# files written by an earlier version decode to the very GLB that version's terminal decoder made
.PHONY: check-old-files
check-old-files: $(CMZ) $(call bdir,terminal)/cmz-decode
	$(Q)tests/tools/check_old_files.sh $(CMZ) $(call bdir,terminal)/cmz-decode tests/data/old_formats

check-bundled-roundtrip: $(CMZ) $(call bdir,terminal)/cmz-decode $(MESH_CHECK) $(CMZ_HEADER)
	$(Q)tests/tools/check_bundled_roundtrip.sh $(CMZ) $(call bdir,terminal)/cmz-decode $(MESH_CHECK) $(CMZ_HEADER) \
		$(wildcard tests/data/*.igs)

# the VM computes, the pty transfers mostly wait (paced like a serial line): run the two side by side
.PHONY: check-hw-and-links
check-hw-and-links: $(CMZ) $(call bdir,terminal)/cmz-terminal $(call bdir,tiny)/cmz-terminal $(call bdir,terminal)/cmz-decode
	$(Q)$(MAKE) --no-print-directory -s serial-tests $(LINK_TEST_BIN) $(GPIO_PROBE) $(GPIO_PROBE_NOGPIO) $(HW_TEST_DEPS)
	$(Q)tests/tools/sum_suites.sh --parallel \
		"tests/tools/sum_suites.sh '$(MAKE) --no-print-directory -s check-hw' '$(MAKE) --no-print-directory -s check-serial'" \
		"tests/tools/sum_suites.sh '$(MAKE) --no-print-directory -s check-link' \
			'$(MAKE) --no-print-directory -s check-link-aarch64' '$(MAKE) --no-print-directory -s check-serial-aarch64'"

# layer (a) of the no-heap gate: the decoder/kernel archive may only call allowlisted libc/libm symbols
check-noheap: $(B)/libcmdecoder.a
	$(Q)tests/tools/check_noheap.sh $(NM) $< tests/tools/noheap_allow.txt

check-stack: $(B)/libcmdecoder.a $(STACK_CHECK)
	$(Q)$(STACK_CHECK) --fn-max $(call limit_of,$(PROFILE),CM_STACK_FN_MAX) \
		--budget $(call limit_of,$(PROFILE),CM_STACK_BUDGET) --indirect tests/tools/stack_indirect_decoder.txt \
		$$(find $(B)/decoder -name '*.ci' | sort)

# gcc built the suites above; clang builds and runs them again with ASan+UBSan
CLANG_SAN := -O1 -g -fsanitize=address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer
check-clang:
	$(Q)$(MAKE) --no-print-directory -s CC=clang BUILD_ROOT=$(BUILD_ROOT)/clang-san CM_NO_STACK_FLAGS=1 \
		CFLAGS="$(CLANG_SAN)" LDFLAGS="-fsanitize=address,undefined" unit-tests-host unit-tests-tiny host-tests-host
	$(Q)CM_SHARED_MODELS=/nonexistent tests/tools/run_suites.sh --quiet \
		"clang-host:$$(ls -d $(BUILD_ROOT)/clang-san/*-host)/tests/unit" \
		"clang-tiny:$$(ls -d $(BUILD_ROOT)/clang-san/*-tiny)/tests/unit" \
		"clang-host-tools:$$(ls -d $(BUILD_ROOT)/clang-san/*-host)/tests/host"

# the IGES import fuzz target replayed under ASan/UBSan: seeds, regressions and the shared corpus
SHARED_MODELS ?= ../shared/models
FUZZ_REPLAY_SHARED ?= $(wildcard $(SHARED_MODELS)/iges)
FUZZ_REPLAY_SHARED_STEP ?= $(wildcard $(SHARED_MODELS)/step)
check-fuzz-replay:
	$(Q)$(MAKE) --no-print-directory -s CC=clang BUILD_ROOT=$(BUILD_ROOT)/clang-san CM_NO_STACK_FLAGS=1 \
		CFLAGS="$(CLANG_SAN)" LDFLAGS="-fsanitize=address,undefined" \
		$(BUILD_ROOT)/clang-san/$(shell clang -dumpmachine 2>/dev/null)-host/tests/fuzz/replay_iges
	$(Q)ASAN_OPTIONS=detect_leaks=1 $(BUILD_ROOT)/clang-san/$(shell clang -dumpmachine 2>/dev/null)-host/tests/fuzz/replay_iges \
		tests/fuzz/corpus_iges $(wildcard tests/fuzz/regressions_iges) $(FUZZ_REPLAY_SHARED)
	$(Q)$(MAKE) --no-print-directory -s CC=clang BUILD_ROOT=$(BUILD_ROOT)/clang-san CM_NO_STACK_FLAGS=1 \
		CFLAGS="$(CLANG_SAN)" LDFLAGS="-fsanitize=address,undefined" \
		$(BUILD_ROOT)/clang-san/$(shell clang -dumpmachine 2>/dev/null)-host/tests/fuzz/replay_step
	$(Q)ASAN_OPTIONS=detect_leaks=1 $(BUILD_ROOT)/clang-san/$(shell clang -dumpmachine 2>/dev/null)-host/tests/fuzz/replay_step \
		tests/fuzz/corpus_step $(wildcard tests/fuzz/regressions_step) $(FUZZ_REPLAY_SHARED_STEP)

# the decode fuzz target (terminal profile, the board's limits) replayed under ASan/UBSan:
# seeds (valid files of every method), named malformed inputs and regressions
CLANG_TRIPLET = $(shell clang -dumpmachine 2>/dev/null)
# (built as the fuzzer is, without CRC checks, so regressions found by fuzz-decode replay here),
# then the same inputs through fuzz_decode_crc on the product build (CRCs and checksums checked)
check-fuzz-decode-replay:
	$(Q)$(MAKE) --no-print-directory -s CC=clang BUILD_ROOT=$(BUILD_ROOT)/clang-san-fuzz CM_NO_STACK_FLAGS=1 PROFILE=terminal \
		CFLAGS="$(CLANG_SAN) -DFUZZING_BUILD_MODE_UNSAFE_FOR_PRODUCTION" LDFLAGS="-fsanitize=address,undefined" \
		$(BUILD_ROOT)/clang-san-fuzz/$(CLANG_TRIPLET)-terminal/tests/fuzz/replay_decode
	$(Q)ASAN_OPTIONS=detect_leaks=1 $(BUILD_ROOT)/clang-san-fuzz/$(CLANG_TRIPLET)-terminal/tests/fuzz/replay_decode \
		tests/fuzz/corpus_decode $(wildcard tests/fuzz/regressions_decode)
	$(Q)$(MAKE) --no-print-directory -s CC=clang BUILD_ROOT=$(BUILD_ROOT)/clang-san CM_NO_STACK_FLAGS=1 PROFILE=terminal \
		CFLAGS="$(CLANG_SAN)" LDFLAGS="-fsanitize=address,undefined" \
		$(BUILD_ROOT)/clang-san/$(CLANG_TRIPLET)-terminal/tests/fuzz/replay_decode_crc
	$(Q)ASAN_OPTIONS=detect_leaks=1 $(BUILD_ROOT)/clang-san/$(CLANG_TRIPLET)-terminal/tests/fuzz/replay_decode_crc \
		tests/fuzz/corpus_decode $(wildcard tests/fuzz/regressions_decode)

# the structure-aware decode fuzzer's replay: like replay_decode, no host code (the generic replay_%
# rule would link libcmhost.a)
define FUZZ_DECODE_CRC_RULES
$(call bdir,$(1))/tests/fuzz/replay_decode_crc: $(call bdir,$(1))/tests/fuzz/fuzz_decode_crc.o \
		$(call bdir,$(1))/tests/fuzz/replay_main.o $(call bdir,$(1))/libcmdecoder.a
	$$(call say,LD      ,$$@)
	$$(Q)$$(CC) $$(CFLAGS) $$(LDFLAGS) -o $$@ $$^ -lm
endef
$(foreach p,$(PROFILES),$(eval $(call FUZZ_DECODE_CRC_RULES,$(p))))

# libFuzzer on the product build of the decoder (not part of check): make fuzz-decode-crc FUZZ_SECONDS=600
# (CRCs and GREGORY checksums checked, as on the terminal; tests/fuzz/fuzz_decode_crc.c's mutator
# lays the file out again and recomputes every CRC after each mutation, and makes the header hostile
# on purpose now and then: section and need counts, table entries, lengths, grid, tolerances;
# 60 s per input: up to 12 faces are tessellated under the instrumentation, a few seconds each on a
# busy machine)
.PHONY: fuzz-decode-crc
fuzz-decode-crc:
	$(Q)$(MAKE) --no-print-directory -s CC=clang BUILD_ROOT=$(BUILD_ROOT)/fuzz-crc CM_NO_STACK_FLAGS=1 PROFILE=terminal \
		CFLAGS="-O1 -g -fsanitize=fuzzer-no-link,address,undefined -fno-sanitize-recover=all $(FUZZ_COVERAGE_IGNORE)" \
		$(BUILD_ROOT)/fuzz-crc/$(FUZZ_TRIPLET)-terminal/tests/fuzz/fuzz_decode_crc.o \
		$(BUILD_ROOT)/fuzz-crc/$(FUZZ_TRIPLET)-terminal/libcmdecoder.a
	$(Q)clang -fsanitize=fuzzer,address,undefined -o $(BUILD_ROOT)/fuzz-crc/fuzz_decode_crc \
		$(BUILD_ROOT)/fuzz-crc/$(FUZZ_TRIPLET)-terminal/tests/fuzz/fuzz_decode_crc.o \
		$(BUILD_ROOT)/fuzz-crc/$(FUZZ_TRIPLET)-terminal/libcmdecoder.a -lm
	$(Q)mkdir -p $(BUILD_ROOT)/fuzz-crc/corpus_decode && cp tests/fuzz/corpus_decode/* $(BUILD_ROOT)/fuzz-crc/corpus_decode/
	$(BUILD_ROOT)/fuzz-crc/fuzz_decode_crc $(FUZZ_ARGS) -max_len=65536 -timeout=60 \
		-artifact_prefix=$(BUILD_ROOT)/fuzz-crc/ $(BUILD_ROOT)/fuzz-crc/corpus_decode

# the triangulator's fuzz target replayed under ASan/UBSan over its seeds (each case family, crashers
# kept as regress_*, inputs the old triangulator refused as old_*), strict: a refusal of loops that do
# not cross is a failure
.PHONY: check-fuzz-tess-replay fuzz-tess
check-fuzz-tess-replay:
	$(Q)$(MAKE) --no-print-directory -s CC=clang BUILD_ROOT=$(BUILD_ROOT)/clang-san CM_NO_STACK_FLAGS=1 PROFILE=terminal \
		CFLAGS="$(CLANG_SAN)" LDFLAGS="-fsanitize=address,undefined" \
		$(BUILD_ROOT)/clang-san/$(CLANG_TRIPLET)-terminal/tests/fuzz/replay_tess
	$(Q)FUZZ_TESS_STRICT=1 $(BUILD_ROOT)/clang-san/$(CLANG_TRIPLET)-terminal/tests/fuzz/replay_tess tests/fuzz/corpus_tess

# the viewer's glTF input's seeds replayed under the sanitizers: each GLB read, drawn, and its faces'
# boxes and both fits compared (tests/fuzz/fuzz_glb.c)
.PHONY: check-fuzz-glb-replay
check-fuzz-glb-replay:
	$(Q)$(MAKE) --no-print-directory -s CC=clang BUILD_ROOT=$(BUILD_ROOT)/clang-san CM_NO_STACK_FLAGS=1 PROFILE=terminal \
		CFLAGS="$(CLANG_SAN)" LDFLAGS="-fsanitize=address,undefined" \
		$(BUILD_ROOT)/clang-san/$(CLANG_TRIPLET)-terminal/tests/fuzz/replay_glb
	$(Q)$(BUILD_ROOT)/clang-san/$(CLANG_TRIPLET)-terminal/tests/fuzz/replay_glb tests/fuzz/corpus_glb

# libFuzzer on the triangulator (not part of check): make fuzz-tess FUZZ_SECONDS=600 (its own build:
# edge coverage of the library only, the harness uninstrumented, about 13x faster)
fuzz-tess:
	$(Q)$(MAKE) --no-print-directory -s CC=clang BUILD_ROOT=$(BUILD_ROOT)/fuzz-tess CM_NO_STACK_FLAGS=1 PROFILE=terminal \
		CFLAGS="-O1 -g -fsanitize=address,undefined -fno-sanitize-recover=all -fsanitize-coverage=inline-8bit-counters,pc-table" \
		$(BUILD_ROOT)/fuzz-tess/$(FUZZ_TRIPLET)-terminal/libcmdecoder.a
	$(Q)clang -O1 -g -std=c11 -ffp-contract=off -fsanitize=address,undefined -fno-sanitize-recover=all $(CM_INC) \
		-DCM_PROFILE='"profiles/terminal.h"' -c tests/fuzz/fuzz_tess.c -o $(BUILD_ROOT)/fuzz-tess/fuzz_tess.o
	$(Q)clang -fsanitize=fuzzer,address,undefined -o $(BUILD_ROOT)/fuzz-tess/fuzz_tess $(BUILD_ROOT)/fuzz-tess/fuzz_tess.o \
		$(BUILD_ROOT)/fuzz-tess/$(FUZZ_TRIPLET)-terminal/libcmdecoder.a -lm
	$(Q)mkdir -p $(BUILD_ROOT)/fuzz-tess/corpus && cp tests/fuzz/corpus_tess/* $(BUILD_ROOT)/fuzz-tess/corpus/
	FUZZ_TESS_STRICT=1 $(BUILD_ROOT)/fuzz-tess/fuzz_tess $(FUZZ_ARGS) -max_len=2048 -timeout=10 \
		-artifact_prefix=$(BUILD_ROOT)/fuzz-tess/ $(BUILD_ROOT)/fuzz-tess/corpus

# libFuzzer on the viewer's glTF input (not part of check): make fuzz-glb FUZZ_SECONDS=600 (its own
# build, as fuzz-tess: the library's coverage only)
.PHONY: fuzz-glb
fuzz-glb:
	$(Q)$(MAKE) --no-print-directory -s CC=clang BUILD_ROOT=$(BUILD_ROOT)/fuzz-glb CM_NO_STACK_FLAGS=1 PROFILE=terminal \
		CFLAGS="-O1 -g -fsanitize=address,undefined -fno-sanitize-recover=all -fsanitize-coverage=inline-8bit-counters,pc-table" \
		$(BUILD_ROOT)/fuzz-glb/$(FUZZ_TRIPLET)-terminal/libcmdecoder.a
	$(Q)clang -O1 -g -std=c11 -ffp-contract=off -fsanitize=address,undefined -fno-sanitize-recover=all $(CM_INC) \
		-DCM_PROFILE='"profiles/terminal.h"' -c tests/fuzz/fuzz_glb.c -o $(BUILD_ROOT)/fuzz-glb/fuzz_glb.o
	$(Q)clang -fsanitize=fuzzer,address,undefined -o $(BUILD_ROOT)/fuzz-glb/fuzz_glb $(BUILD_ROOT)/fuzz-glb/fuzz_glb.o \
		$(BUILD_ROOT)/fuzz-glb/$(FUZZ_TRIPLET)-terminal/libcmdecoder.a -lm
	$(Q)mkdir -p $(BUILD_ROOT)/fuzz-glb/corpus && cp tests/fuzz/corpus_glb/* $(BUILD_ROOT)/fuzz-glb/corpus/
	$(BUILD_ROOT)/fuzz-glb/fuzz_glb $(FUZZ_ARGS) -max_len=16384 -timeout=10 \
		-artifact_prefix=$(BUILD_ROOT)/fuzz-glb/ $(BUILD_ROOT)/fuzz-glb/corpus

# libFuzzer on the decoder (not part of check): make fuzz-decode FUZZ_SECONDS=600
# (built without CRC checks, in build/fuzz only, so that mutations reach the section decoders)
.PHONY: fuzz-decode
fuzz-decode:
	$(Q)$(MAKE) --no-print-directory -s CC=clang BUILD_ROOT=$(BUILD_ROOT)/fuzz CM_NO_STACK_FLAGS=1 PROFILE=terminal \
		CFLAGS="-O1 -g -fsanitize=fuzzer-no-link,address,undefined -fno-sanitize-recover=all -DFUZZING_BUILD_MODE_UNSAFE_FOR_PRODUCTION $(FUZZ_COVERAGE_IGNORE)" \
		$(BUILD_ROOT)/fuzz/$(FUZZ_TRIPLET)-terminal/tests/fuzz/fuzz_decode.o \
		$(BUILD_ROOT)/fuzz/$(FUZZ_TRIPLET)-terminal/libcmdecoder.a
	$(Q)clang -fsanitize=fuzzer,address,undefined -o $(BUILD_ROOT)/fuzz/fuzz_decode \
		$(BUILD_ROOT)/fuzz/$(FUZZ_TRIPLET)-terminal/tests/fuzz/fuzz_decode.o \
		$(BUILD_ROOT)/fuzz/$(FUZZ_TRIPLET)-terminal/libcmdecoder.a -lm
	$(Q)mkdir -p $(BUILD_ROOT)/fuzz/corpus_decode && cp tests/fuzz/corpus_decode/* $(BUILD_ROOT)/fuzz/corpus_decode/
	$(BUILD_ROOT)/fuzz/fuzz_decode $(FUZZ_ARGS) -max_len=65536 -timeout=30 \
		-artifact_prefix=$(BUILD_ROOT)/fuzz/ $(BUILD_ROOT)/fuzz/corpus_decode

# libFuzzer on the STEP import (not part of check): make fuzz-step FUZZ_SECONDS=600
.PHONY: fuzz-step
fuzz-step:
	$(Q)$(MAKE) --no-print-directory -s CC=clang BUILD_ROOT=$(BUILD_ROOT)/fuzz CM_NO_STACK_FLAGS=1 \
		CFLAGS="-O1 -g -fsanitize=fuzzer-no-link,address,undefined -fno-sanitize-recover=all $(FUZZ_COVERAGE_IGNORE)" \
		$(BUILD_ROOT)/fuzz/$(FUZZ_TRIPLET)-host/tests/fuzz/fuzz_step.o \
		$(BUILD_ROOT)/fuzz/$(FUZZ_TRIPLET)-host/libcmhost.a $(BUILD_ROOT)/fuzz/$(FUZZ_TRIPLET)-host/libcmdecoder.a
	$(Q)clang -fsanitize=fuzzer,address,undefined -o $(BUILD_ROOT)/fuzz/fuzz_step \
		$(BUILD_ROOT)/fuzz/$(FUZZ_TRIPLET)-host/tests/fuzz/fuzz_step.o \
		$(BUILD_ROOT)/fuzz/$(FUZZ_TRIPLET)-host/libcmhost.a $(BUILD_ROOT)/fuzz/$(FUZZ_TRIPLET)-host/libcmdecoder.a -lm
	$(Q)mkdir -p $(BUILD_ROOT)/fuzz/corpus_step && cp tests/fuzz/corpus_step/* $(BUILD_ROOT)/fuzz/corpus_step/
	$(BUILD_ROOT)/fuzz/fuzz_step $(FUZZ_ARGS) -max_len=4194304 -timeout=120 \
		-artifact_prefix=$(BUILD_ROOT)/fuzz/ $(BUILD_ROOT)/fuzz/corpus_step $(wildcard $(SHARED_MODELS)/step)

# libFuzzer on the IGES import (not part of check): make fuzz-iges FUZZ_SECONDS=600
# (max_len 4 MiB: the corpus models, up to 3.9 MB, are seeds whole, not cut at the default length)
FUZZ_SECONDS ?= 60
# what every fuzz-* target passes libFuzzer: a time budget, or e.g. FUZZ_ARGS="-runs=1000000"
FUZZ_ARGS ?= -max_total_time=$(FUZZ_SECONDS) -print_final_stats=1
FUZZ_TRIPLET = $(shell clang -dumpmachine 2>/dev/null)
# the fuzzers leave the B-spline evaluator and the triangulator uninstrumented for coverage (why: the file itself)
FUZZ_COVERAGE_IGNORE = -fsanitize-coverage-ignorelist=$(CURDIR)/tests/fuzz/coverage_ignore.txt
.PHONY: fuzz-iges
fuzz-iges:
	$(Q)$(MAKE) --no-print-directory -s CC=clang BUILD_ROOT=$(BUILD_ROOT)/fuzz CM_NO_STACK_FLAGS=1 \
		CFLAGS="-O1 -g -fsanitize=fuzzer-no-link,address,undefined -fno-sanitize-recover=all $(FUZZ_COVERAGE_IGNORE)" \
		$(BUILD_ROOT)/fuzz/$(FUZZ_TRIPLET)-host/tests/fuzz/fuzz_iges.o \
		$(BUILD_ROOT)/fuzz/$(FUZZ_TRIPLET)-host/libcmhost.a $(BUILD_ROOT)/fuzz/$(FUZZ_TRIPLET)-host/libcmdecoder.a
	$(Q)clang -fsanitize=fuzzer,address,undefined -o $(BUILD_ROOT)/fuzz/fuzz_iges \
		$(BUILD_ROOT)/fuzz/$(FUZZ_TRIPLET)-host/tests/fuzz/fuzz_iges.o \
		$(BUILD_ROOT)/fuzz/$(FUZZ_TRIPLET)-host/libcmhost.a $(BUILD_ROOT)/fuzz/$(FUZZ_TRIPLET)-host/libcmdecoder.a -lm
	$(Q)mkdir -p $(BUILD_ROOT)/fuzz/corpus_iges && cp tests/fuzz/corpus_iges/* $(BUILD_ROOT)/fuzz/corpus_iges/
	$(BUILD_ROOT)/fuzz/fuzz_iges $(FUZZ_ARGS) -max_len=4194304 -timeout=120 \
		-artifact_prefix=$(BUILD_ROOT)/fuzz/ $(BUILD_ROOT)/fuzz/corpus_iges $(wildcard $(SHARED_MODELS)/iges)

# the import against Open CASCADE on the shared corpus (skips without it)
check-corpus-occt: $(CMZ) oracle
	$(Q)tests/tools/check_corpus_occt.sh $(CMZ) $(ORACLE_BIN) $(SHARED_MODELS)

# the STEP import against Open CASCADE's STEP reader: faces, free edges, diagonal, points (skips without it)
check-step-occt: $(CMZ) oracle
	$(Q)tests/tools/check_step_occt.sh $(CMZ) $(ORACLE_BIN) $(SHARED_MODELS)

# STEP -> .cmz -> decode -> mesh on the shared corpus's STEP models, judged as the IGES ones (skips without it)
check-step-roundtrip: $(CMZ) $(MESH_CHECK) oracle gltf-check-tool
	$(Q)tests/tools/check_corpus_roundtrip.sh $(CMZ) $(MESH_CHECK) $(ORACLE_BIN) $(GLTF_CHECK_BIN) $(SHARED_MODELS) step

# encode -> decode -> mesh on the shared corpus, judged by mesh_check, OCCT, tinygltf and cmz eval
# (skips without it)
check-corpus-roundtrip: $(CMZ) $(MESH_CHECK) oracle gltf-check-tool
	$(Q)tests/tools/check_corpus_roundtrip.sh $(CMZ) $(MESH_CHECK) $(ORACLE_BIN) $(GLTF_CHECK_BIN) $(SHARED_MODELS)

# cmz-decode for aarch64 under qemu-user and built at -O0: byte-identical GLB on every model (the
# GREGORY checksums of the x86-64 -O2 encoder verified by each: spec §17 T11); tiny refuses by limit
# (the host profile's limits are too large for static arrays: there `cmz decode`, same decoder, is compared)
check-decode-cross: $(CMZ) $(call bdir,terminal)/cmz-decode $(call bdir,tiny)/cmz-decode
	$(Q)$(MAKE) --no-print-directory -s CROSS_COMPILE=aarch64-linux-gnu- CC=aarch64-linux-gnu-gcc AR=aarch64-linux-gnu-ar \
		PKG_CONFIG=aarch64-linux-gnu-pkg-config $(BUILD_ROOT)/aarch64-linux-gnu-terminal/cmz-decode \
		$(BUILD_ROOT)/aarch64-linux-gnu-host/cmz
	$(Q)$(MAKE) --no-print-directory -s BUILD_ROOT=$(BUILD_ROOT)/O0 CFLAGS="-O0 -g" CM_NO_STACK_FLAGS=1 PROFILE=terminal \
		$(BUILD_ROOT)/O0/$(TRIPLET)-terminal/cmz-decode
	$(Q)tests/tools/check_decode_cross.sh $(CMZ) $(BUILD_ROOT) $(SHARED_MODELS)

# what the terminal shows (issue 17): cmz-view on the bundled models, every direction and in
# perspective (valid PNG, the model inside the margin and fitted, the same bytes twice; a frame
# beyond the build's and a truncated file refused); check-view-cross also draws them with the
# aarch64 build under qemu-user: the same pixels
check-view: $(CMZ) $(call bdir,terminal)/cmz-view
	$(Q)tests/tools/check_view.sh $(CMZ) $(call bdir,terminal)/cmz-view
check-view-cross: $(CMZ) $(call bdir,terminal)/cmz-view
	$(Q)$(MAKE) --no-print-directory -s CROSS_COMPILE=aarch64-linux-gnu- CC=aarch64-linux-gnu-gcc AR=aarch64-linux-gnu-ar \
		PKG_CONFIG=aarch64-linux-gnu-pkg-config $(BUILD_ROOT)/aarch64-linux-gnu-terminal/cmz-view
	$(Q)tests/tools/check_view.sh $(CMZ) $(call bdir,terminal)/cmz-view $(BUILD_ROOT)/aarch64-linux-gnu-terminal/cmz-view

# what the terminal shows against an independent renderer (issue 17): the GLB `cmz decode` writes,
# drawn by three.js in headless Chromium with cmz-view's camera: silhouettes (IoU >= 0.98) and each
# face's colour (tests/tools/three_check.py), with an upside-down control that must fail
check-three: $(CMZ) $(call bdir,terminal)/cmz-view
	$(Q)tests/tools/check_three.sh $(CMZ) $(call bdir,terminal)/cmz-view $(SHARED_MODELS)

# unit tests of the ARM builds under qemu-user, and bit-identical kernel values against this machine
check-cross: $(call bdir,host)/tests/unit/kernel_vectors
	$(Q)for x in $(CROSS_TARGETS); do \
		$(MAKE) --no-print-directory -s CROSS_COMPILE=$$x CC=$${x}gcc AR=$${x}ar PKG_CONFIG=$${x}pkg-config \
			unit-tests-host unit-tests-terminal || exit 1; \
	done
	$(Q)tests/tools/check_cross.sh $(BUILD_ROOT) $(call bdir,host)/tests/unit/kernel_vectors $(CROSS_TARGETS)

# ---- Debian packages ----
# Host tools, tests, cross toolchains and the foreign-architecture libraries the cross tests link;
# libusb and libgpiod (1.6) for the terminal, also for arm64; the test VM of check-hw (qemu, the
# Debian kernel's headers for gpio-sim, busybox for the initramfs); Chromium and three.js for
# check-three.  armhf builds the terminal without USB and GPIO (no :armhf libusb/libgpiod here:
# Multi-Arch versions, hw-testing NOTES 10).
DEPS_ARCHS := arm64 armhf
DEPS_PKGS := gcc g++ make pkgconf libcmocka-dev clang libclang-rt-14-dev libfuzzer-14-dev \
	libtinygltf-dev nlohmann-json3-dev \
	libocct-data-exchange-dev libocct-modeling-algorithms-dev libocct-modeling-data-dev libocct-foundation-dev \
	gcc-aarch64-linux-gnu gcc-arm-linux-gnueabihf libc6-dev-arm64-cross libc6-dev-armhf-cross qemu-user \
	pkgconf:arm64 pkgconf:armhf libcmocka-dev:arm64 libcmocka-dev:armhf \
	libusb-1.0-0-dev libgpiod-dev libusb-1.0-0-dev:arm64 libgpiod-dev:arm64 libdrm-dev libdrm-dev:arm64 \
	qemu-system-x86 busybox-static cpio kmod xz-utils linux-headers-amd64 usbutils gpiod strace python3 \
	chromium libjs-three
deps:
	$(Q)DEPS_ARCHS="$(DEPS_ARCHS)" tests/tools/deps.sh $(DEPS_PKGS)

# ---- README's generated tables (limits of every profile, error codes) ----
.PHONY: readme check-readme
readme: $(LIMIT_TOOLS)
	$(Q)tests/tools/readme_tables.sh $(BUILD_ROOT) $(TRIPLET)
check-readme: $(LIMIT_TOOLS)
	$(Q)tests/tools/readme_tables.sh --check $(BUILD_ROOT) $(TRIPLET)

# ---- demo (needs the encoder and decoder of later work) ----
.PHONY: demo bench
# the main job on a bundled model: packages for building, then encode on the "workstation" and
# decode with the terminal's heap-free decoder (terminal profile) into out/demo.glb
DEMO_MODEL ?= tests/data/as1_pe_203.igs
DEMO_PKGS := gcc make xz-utils gzip
demo:
	$(Q)DEPS_ARCHS= tests/tools/deps.sh $(DEMO_PKGS)
	$(Q)$(MAKE) --no-print-directory -s $(CMZ) $(call bdir,terminal)/cmz-decode
	$(Q)host_tools/scripts/demo.sh $(CMZ) $(call bdir,terminal)/cmz-decode $(DEMO_MODEL) out

# size, speed and memory on the bundled models and the shared corpus (not part of check), then the
# same models against xz -9e, Open CASCADE's mesh + Draco and Open CASCADE's read + mesh (one run);
# BENCH_CALLGRIND=1 adds the decoders' instruction counts (valgrind)
BENCH_MODELS ?= $(wildcard tests/data/*.igs) $(wildcard $(SHARED_MODELS)/iges/*) $(wildcard $(SHARED_MODELS)/step/*)
bench:
	$(Q)DEPS_ARCHS= tests/tools/deps.sh $(DEMO_PKGS) time bc valgrind draco \
		libocct-data-exchange-dev libocct-modeling-algorithms-dev libocct-modeling-data-dev libocct-foundation-dev
	$(Q)$(MAKE) --no-print-directory -s $(CMZ) $(call bdir,terminal)/cmz-decode $(ORACLE_BIN) $(WALL_MIN)
	$(Q)WALL_MIN=$(WALL_MIN) host_tools/scripts/bench.sh $(CMZ) $(call bdir,terminal)/cmz-decode $(BUILD_ROOT)/bench $(BENCH_MODELS)
	$(Q)WALL_MIN=$(WALL_MIN) host_tools/scripts/bench_peers.sh $(CMZ) $(call bdir,terminal)/cmz-decode $(ORACLE_BIN) $(BUILD_ROOT)/bench $(BENCH_MODELS)
	$(Q)$(MAKE) --no-print-directory -s $(call bdir,terminal)/cmz-view
	$(Q)$(MAKE) --no-print-directory -s CROSS_COMPILE=aarch64-linux-gnu- CC=aarch64-linux-gnu-gcc AR=aarch64-linux-gnu-ar \
		PKG_CONFIG=aarch64-linux-gnu-pkg-config $(BUILD_ROOT)/aarch64-linux-gnu-terminal/cmz-view || true
	$(Q)host_tools/scripts/bench_view.sh $(call bdir,terminal)/cmz-view $(BUILD_ROOT)/bench \
		$(BUILD_ROOT)/aarch64-linux-gnu-terminal/cmz-view
	$(Q)$(MAKE) --no-print-directory -s bench-link

# the link's speed: cmz send -> cmz-terminal over ptys, unpaced, paced at 115200 baud, and noisy
.PHONY: bench-link
BENCH_LINK_MODELS ?= tests/data/as1_pe_203.igs tests/data/geo_example.igs
bench-link: $(CMZ) $(call bdir,terminal)/cmz-terminal $(call bdir,host)/tests/tools/pty_relay
	$(Q)mkdir -p $(BUILD_ROOT)/bench
	$(Q)for m in $(BENCH_LINK_MODELS); do $(CMZ) encode -q $$m -o $(BUILD_ROOT)/bench/link-$$(basename $${m%.*}).cmz \
		> /dev/null || exit 1; done
	$(Q)host_tools/scripts/bench_link.sh $(CMZ) $(call bdir,terminal)/cmz-terminal $(call bdir,host)/tests/tools/pty_relay \
		$(BUILD_ROOT)/bench $(patsubst %,$(BUILD_ROOT)/bench/link-%.cmz,$(basename $(notdir $(BENCH_LINK_MODELS))))

# ---- install / clean ----
# The workstation's cmz (host profile) and cmz-usb-gadget.sh; the terminal's cmz-decode and cmz-terminal
# and cm-limits, built with PROFILE (terminal by default) as `make` builds them; the udev rules example
# (README "udev rules") and the LICENSE under DOCDIR.  A cross build installs the board's binaries:
#   make install CROSS_COMPILE=aarch64-linux-gnu- PREFIX=/usr DESTDIR=/tmp/stage
DOCDIR ?= $(PREFIX)/share/doc/curvemesh
INSTALL_PROGS := $(CMZ) host_tools/scripts/cmz-usb-gadget.sh $(B)/cmz-decode $(B)/cmz-view $(B)/cmz-terminal \
                 $(B)/cm-limits
INSTALL_DOCS := platform/99-cmz-terminal.rules.example LICENSE
.PHONY: install clean
install: $(INSTALL_PROGS) $(INSTALL_DOCS)
	install -d -m 0755 $(DESTDIR)$(BINDIR) $(DESTDIR)$(DOCDIR)
	install -m 0755 $(INSTALL_PROGS) $(DESTDIR)$(BINDIR)/
	install -m 0644 $(INSTALL_DOCS) $(DESTDIR)$(DOCDIR)/

clean:
	rm -rf $(BUILD_ROOT)

# ---- hostile input (issue 10): mutated IGES and .cmz files against cmz and the terminal's decoder ----
MUTATE := $(call bdir,host)/tests/tools/mutate
$(MUTATE): $(call bdir,host)/tests/tools/mutate.o $(call bdir,host)/libcmdecoder.a
	$(call say,LD      ,$@)
	$(Q)$(CC) $(CFLAGS) $(LDFLAGS) -o $@ $^ -lm
# make hostile [HOSTILE_TRIES=N]: the table of README "Hostile input" (not part of check; check runs a
# few tries).  cmz and the terminal's cmz-decode are built with ASan and UBSan, so that an access out of
# bounds inside a struct or an undefined conversion counts as the crash it is.
HOSTILE_TRIES ?= 40
HOSTILE_SAN := $(BUILD_ROOT)/clang-san/$(CLANG_TRIPLET)
.PHONY: hostile hostile-tools
hostile-tools: $(MUTATE)
	$(Q)$(MAKE) --no-print-directory -s CC=clang BUILD_ROOT=$(BUILD_ROOT)/clang-san CM_NO_STACK_FLAGS=1 \
		CFLAGS="$(CLANG_SAN)" LDFLAGS="-fsanitize=address,undefined" \
		$(HOSTILE_SAN)-host/cmz $(HOSTILE_SAN)-terminal/cmz-decode
hostile: hostile-tools
	$(Q)ASAN_OPTIONS=detect_leaks=0 tests/tools/hostile_run.sh $(HOSTILE_SAN)-host/cmz $(HOSTILE_SAN)-terminal/cmz-decode \
		$(MUTATE) $(BUILD_ROOT)/hostile $(HOSTILE_TRIES) $(HOSTILE_TAP)

# one bad face never sinks a model, from the command line (encode, --strict, eval, decode)
.PHONY: check-leave-out
check-leave-out: $(CMZ) $(call bdir,host)/tests/host/test_leave_out
	$(Q)tests/tools/check_leave_out.sh $(CMZ) $(call bdir,host)/tests/host/test_leave_out $(BUILD_ROOT)/leave-out

# `cmz encode FOLDER -o OUT` over a vault of the bundled models (issue 15.5): a bad model named while
# the rest encode, up-to-date outputs skipped, --timeout, shards, lists, interrupts
# cmz encode -j 3 writes the bytes of -j 1 on every corpus model (the faces' work on worker processes)
.PHONY: check-encode-jobs
check-encode-jobs: $(CMZ)
	$(Q)tests/tools/check_encode_jobs.sh $(CMZ) $(SHARED_MODELS)

.PHONY: check-vault
check-vault: $(CMZ) $(call bdir,host)/tests/host/test_leave_out
	$(Q)tests/tools/check_vault.sh $(CMZ) $(call bdir,host)/tests/host/test_leave_out tests/data/geo_example.igs \
		tests/data/as1_pe_203.igs
