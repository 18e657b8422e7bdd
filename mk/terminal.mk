# mk/terminal.mk - the link protocol, cmz-terminal and the transports in `cmz` (send).
#
#   make                      also builds $(B)/cmz-terminal for PROFILE (terminal by default)
#   make CROSS_COMPILE=aarch64-linux-gnu-   the same for the board (needs make deps)
#   make check-link           link protocol unit tests, and cmz send -> cmz-terminal over ptys
#                             through a fault-injecting relay (tests/link/)
#
# USB needs libusb-1.0 >= 1.0.26 (Debian 12) for this machine's architecture (the :arm64 package
# for the aarch64 build); without it the programs build without --usb and say so when asked.

LINK_USB := $(shell $(PKG_CONFIG) --atleast-version=1.0.26 libusb-1.0 2>/dev/null && echo 1)
ifeq ($(LINK_USB),1)
LINK_USB_CFLAGS := -DCM_HAVE_LIBUSB $(shell $(PKG_CONFIG) --cflags libusb-1.0)
LINK_USB_LIBS := $(shell $(PKG_CONFIG) --libs libusb-1.0)
endif
# the GPIO back end (mk/hw.mk picks libgpiod 1.6 when present)
GPIO_SRC ?= platform/cm_gpio_none.c
GPIO_CFLAGS ?=
GPIO_LIBS ?=

# the protocol and the transports every build has
LINK_COMMON_SRC := platform/cm_link.c platform/cm_transport_fd.c platform/cm_transport_serial.c
LINK_TERM_SRC := $(LINK_COMMON_SRC) platform/cm_link_term.c $(if $(LINK_USB),platform/cm_transport_usb.c)
LINK_HOST_SRC := $(LINK_COMMON_SRC) $(if $(LINK_USB),platform/cm_transport_usb.c platform/cm_transport_ffs.c)

# the USB and GPIO objects, and whoever asks for them, see the libraries' headers
$(foreach p,$(PROFILES),$(call bdir,$(p))/platform/cmz_terminal_main.o $(call bdir,$(p))/platform/cm_transport_usb.o \
	$(call bdir,$(p))/platform/cm_transport_ffs.o $(call bdir,$(p))/host_tools/send/send_cmd.o): \
	CPPFLAGS += $(LINK_USB_CFLAGS)

# cmz-terminal: the board's daemon (no heap on the decode path: linked with the abort wrappers,
# platform/cm_noheap_wrap.c)
define TERMINAL_RULES
$(call bdir,$(1))/cmz-terminal: $(call bdir,$(1))/platform/cmz_terminal_main.o \
		$(patsubst %.c,$(call bdir,$(1))/%.o,$(LINK_TERM_SRC) $(GPIO_SRC)) \
		$(call bdir,$(1))/platform/cm_decode_file.o $(call bdir,$(1))/platform/cm_report.o \
		$(call bdir,$(1))/platform/cm_noheap_wrap.o $(call bdir,$(1))/libcmdecoder.a
	$$(call say,LD      ,$$@)
	$$(Q)$$(CC) $$(CFLAGS) $$(LDFLAGS) $$(CM_GC_SECTIONS) $$(NOHEAP_WRAP) -o $$@ $$^ $$(LINK_USB_LIBS) $$(GPIO_LIBS) -lm
endef
$(foreach p,$(PROFILES),$(eval $(call TERMINAL_RULES,$(p))))
# cmz-view's buttons (issue 17): the GPIO back end too (its libraries in the Makefile's link rule)
$(foreach p,$(PROFILES),$(eval $(call bdir,$(p))/cmz-view: $(call gpio_obj,$(p))))

CMZ_EXTRA_OBJS += $(patsubst %.c,$(call bdir,host)/%.o,$(LINK_HOST_SRC))
CMZ_EXTRA_LIBS += $(LINK_USB_LIBS)
all: $(B)/cmz-terminal

# ---- tests ----
LINK_TEST_BIN := $(call bdir,terminal)/tests/link/test_link
$(LINK_TEST_BIN): $(call bdir,terminal)/tests/link/test_link.o \
		$(patsubst %.c,$(call bdir,terminal)/%.o,$(LINK_COMMON_SRC) platform/cm_link_term.c \
			platform/fake/cm_transport_fault.c platform/fake/cm_transport_mem.c host_tools/send/link_send.c) \
		$(call bdir,terminal)/platform/cm_report.o $(call bdir,terminal)/libcmdecoder.a
	$(call say,LD      ,$@)
	$(Q)$(CC) $(CFLAGS) $(LDFLAGS) -o $@ $^ -lm

.PHONY: check-link
check-link: $(LINK_TEST_BIN) $(CMZ) $(call bdir,terminal)/cmz-terminal $(call bdir,tiny)/cmz-terminal \
		$(call bdir,host)/tests/tools/pty_relay $(call bdir,terminal)/cmz-decode
	$(Q)tests/tools/sum_suites.sh "$(LINK_TEST_BIN) tests/fuzz/corpus_decode/as1_pe_203_v3_chunk0.cmzf" \
		"$(LINK_RECOVERY_BIN) tests/fuzz/corpus_decode/as1_pe_203_chunk0.cmzf" \
		"TINY_TERMINAL=$(call bdir,tiny)/cmz-terminal tests/link/check_link_pty.sh $(CMZ) \
		$(call bdir,terminal)/cmz-terminal $(call bdir,host)/tests/tools/pty_relay $(call bdir,terminal)/cmz-decode 50"

# the end-to-end test in the VM (tests/hw/vm-terminal.sh: USB gadget -> libusb, gpio-sim lines)
HW_MODELS := $(BUILD_ROOT)/hw-models
HW_TEST_DEPS += $(CMZ) $(call bdir,terminal)/cmz-terminal $(HW_MODELS)/as1_pe_203.cmz $(HW_MODELS)/geo_example.cmz
HW_TEST_ENV += HW_CMZ=$(CMZ) HW_TERMINAL=$(call bdir,terminal)/cmz-terminal HW_MODELS=$(HW_MODELS)
# the viewer on a kernel framebuffer (tests/hw/vm-display.sh: vfb)
HW_TEST_DEPS += $(call bdir,terminal)/cmz-view
HW_TEST_ENV += HW_VIEW=$(call bdir,terminal)/cmz-view
$(HW_MODELS)/%.cmz: tests/data/%.igs $(CMZ)
	@mkdir -p $(@D)
	$(Q)$(CMZ) encode -q $< -o $@ > /dev/null

# the board's build under qemu-user: the link unit tests and the pty transfers with the aarch64
# cmz-terminal, 5 noisy transfers (the workstation side stays this machine's cmz)
A64 := CROSS_COMPILE=aarch64-linux-gnu- CC=aarch64-linux-gnu-gcc AR=aarch64-linux-gnu-ar PKG_CONFIG=aarch64-linux-gnu-pkg-config
A64_B := $(BUILD_ROOT)/aarch64-linux-gnu-terminal
.PHONY: check-link-aarch64
check-link-aarch64: $(CMZ) $(call bdir,host)/tests/tools/pty_relay $(call bdir,terminal)/cmz-decode \
		$(call bdir,tiny)/cmz-terminal
	$(Q)$(MAKE) --no-print-directory -s $(A64) $(A64_B)/cmz-terminal $(A64_B)/tests/link/test_link
	$(Q)tests/tools/sum_suites.sh "qemu-aarch64 $(A64_B)/tests/link/test_link tests/fuzz/corpus_decode/as1_pe_203_v3_chunk0.cmzf" \
		"TERMINAL_EMU=qemu-aarch64 TINY_TERMINAL=$(call bdir,tiny)/cmz-terminal tests/link/check_link_pty.sh $(CMZ) $(A64_B)/cmz-terminal \
		$(call bdir,host)/tests/tools/pty_relay $(call bdir,terminal)/cmz-decode 5"

# the link's fuzz target (tests/fuzz/fuzz_link.c): replayed under ASan/UBSan in check over seeds that
# test_link writes (a whole transfer: clean, noisy, cut); make fuzz-link FUZZ_SECONDS=600 runs libFuzzer
LINK_FUZZ_OBJS = $(patsubst %.c,$(1)/%.o,platform/cm_link.c platform/cm_link_term.c platform/cm_report.c \
	platform/fake/cm_transport_mem.c tests/fuzz/fuzz_link.c)
LINK_SAN_B = $(BUILD_ROOT)/clang-san/$(CLANG_TRIPLET)-terminal
# (an explicit rule: it must win over the generic replay_% rule, which links the host library)
$(call bdir,terminal)/tests/fuzz/replay_link: $(call LINK_FUZZ_OBJS,$(call bdir,terminal)) \
		$(call bdir,terminal)/tests/fuzz/replay_main.o $(call bdir,terminal)/libcmdecoder.a
	$(call say,LD      ,$@)
	$(Q)$(CC) $(CFLAGS) $(LDFLAGS) -o $@ $^ -lm
.PHONY: check-fuzz-link-replay fuzz-link
check-fuzz-link-replay: $(LINK_TEST_BIN)
	$(Q)mkdir -p $(BUILD_ROOT)/link-seeds
	$(Q)$(LINK_TEST_BIN) tests/fuzz/corpus_decode/as1_pe_203_v3_chunk0.cmzf --write-seeds $(BUILD_ROOT)/link-seeds
	$(Q)$(MAKE) --no-print-directory -s CC=clang BUILD_ROOT=$(BUILD_ROOT)/clang-san CM_NO_STACK_FLAGS=1 PROFILE=terminal \
		CFLAGS="$(CLANG_SAN)" LDFLAGS="-fsanitize=address,undefined" $(LINK_SAN_B)/tests/fuzz/replay_link
	$(Q)ASAN_OPTIONS=detect_leaks=1 $(LINK_SAN_B)/tests/fuzz/replay_link $(BUILD_ROOT)/link-seeds
fuzz-link: $(LINK_TEST_BIN)
	$(Q)mkdir -p $(BUILD_ROOT)/fuzz-link/corpus_link
	$(Q)$(LINK_TEST_BIN) tests/fuzz/corpus_decode/as1_pe_203_v3_chunk0.cmzf --write-seeds $(BUILD_ROOT)/fuzz-link/corpus_link
	$(Q)$(MAKE) --no-print-directory -s CC=clang BUILD_ROOT=$(BUILD_ROOT)/fuzz-link CM_NO_STACK_FLAGS=1 PROFILE=terminal \
		CFLAGS="-O1 -g -fsanitize=fuzzer-no-link,address,undefined -fno-sanitize-recover=all $(FUZZ_DECODE_IGNORE)" \
		$(call LINK_FUZZ_OBJS,$(BUILD_ROOT)/fuzz-link/$(FUZZ_TRIPLET)-terminal) $(BUILD_ROOT)/fuzz-link/$(FUZZ_TRIPLET)-terminal/libcmdecoder.a
	$(Q)clang -fsanitize=fuzzer,address,undefined -o $(BUILD_ROOT)/fuzz-link/fuzz_link \
		$(call LINK_FUZZ_OBJS,$(BUILD_ROOT)/fuzz-link/$(FUZZ_TRIPLET)-terminal) $(BUILD_ROOT)/fuzz-link/$(FUZZ_TRIPLET)-terminal/libcmdecoder.a -lm
	$(BUILD_ROOT)/fuzz-link/fuzz_link $(FUZZ_ARGS) -max_len=65536 -timeout=30 \
		-artifact_prefix=$(BUILD_ROOT)/fuzz-link/ $(BUILD_ROOT)/fuzz-link/corpus_link

# the displayed model's store (platform/cm_term_store.c, generations behind one symlink): only the
# daemon shows models, so only it links the store.  A prerequisite here joins the rule's $^ after
# libcmdecoder.a: the store may only call what the daemon's other objects already use from it
# (cm_fail, cm_status_init), or the link fails naming the symbol
$(foreach p,$(PROFILES),$(eval $(call bdir,$(p))/cmz-terminal: $(call bdir,$(p))/platform/cm_term_store.o))

# issue 11: cmz-terminal killed (CM_TERM_KILL_AT) at every step of storing a model, restarted, the
# sender finishing: the directory always shows one whole model, the delivered one in the end
.PHONY: check-store-kill
check-store-kill: $(CMZ) $(call bdir,terminal)/cmz-terminal $(call bdir,host)/tests/tools/pty_relay \
		$(call bdir,terminal)/cmz-decode
	$(Q)tests/link/check_store_kill.sh $(CMZ) $(call bdir,terminal)/cmz-terminal \
		$(call bdir,host)/tests/tools/pty_relay $(call bdir,terminal)/cmz-decode

# issue 11 part 3: how fast the link recovers (a stalled partial frame, a flood of headers, a stopped
# send, a terminal that forgets transfers, 5 % + 5 % bad bytes); part of check-link
LINK_RECOVERY_BIN := $(call bdir,terminal)/tests/link/test_link_recovery
$(LINK_RECOVERY_BIN): $(call bdir,terminal)/tests/link/test_link_recovery.o \
		$(patsubst %.c,$(call bdir,terminal)/%.o,$(LINK_COMMON_SRC) platform/cm_link_term.c \
			platform/fake/cm_transport_fault.c host_tools/send/link_send.c) \
		$(call bdir,terminal)/platform/cm_report.o $(call bdir,terminal)/libcmdecoder.a
	$(call say,LD      ,$@)
	$(Q)$(CC) $(CFLAGS) $(LDFLAGS) -o $@ $^ -lm
check-link: $(LINK_RECOVERY_BIN)
.PHONY: check-link-recovery
check-link-recovery: $(LINK_RECOVERY_BIN)
	$(Q)$(LINK_RECOVERY_BIN) tests/fuzz/corpus_decode/as1_pe_203_chunk0.cmzf

# ---- the stack gate over whole terminal programs (issue 15.3) ----
# cmz-decode's and cmz-terminal's own code (main, link, transports, GPIO, store, writers) is compiled
# again here with the call graph on, and checked with the decoder's: no frame over CM_STACK_FN_MAX,
# no recursion, every indirect call resolved by tests/tools/stack_indirect.txt, the deepest path
# within CM_STACK_PROGRAM_BUDGET (libc, libusb and libgpiod frames are not seen: the budget leaves
# them the rest of a small thread's stack).  gcc only (clang writes no call graph).
STACK_PROGRAM_SRC := platform/cmz_decode_main.c platform/cmz_view_main.c platform/cm_fb.c platform/cm_decode_file.c \
	platform/cm_report.c \
	platform/cmz_terminal_main.c platform/cm_term_store.c $(LINK_TERM_SRC) $(GPIO_SRC)
STACK_PROGRAM_CI := $(patsubst %.c,$(B)/stackgate/%.ci,$(STACK_PROGRAM_SRC))
$(B)/stackgate/%.ci: %.c
	@mkdir -p $(@D)
	$(call say,CC-STACK,$@)
	$(Q)$(CC) $(CM_INC_ALL) -DCM_PROFILE='"profiles/$(PROFILE).h"' $(LINK_USB_CFLAGS) $(GPIO_CFLAGS) $(CM_STD) \
		$(CM_WARN) $(call stack_flags,$(PROFILE)) $(CFLAGS) $(if $(filter platform/%,$<),$(CM_PLATFORM_OPT)) \
		-c $< -o $(@:.ci=.o)

.PHONY: check-stack-programs
check-stack-programs: $(B)/libcmdecoder.a $(BUILD_ROOT)/tools/check_stack $(STACK_PROGRAM_CI)
	$(Q)$(STACK_CHECK) --fn-max $(call limit_of,$(PROFILE),CM_STACK_FN_MAX) \
		--budget $(call limit_of,$(PROFILE),CM_STACK_PROGRAM_BUDGET) --indirect tests/tools/stack_indirect.txt \
		$$(find $(B)/decoder -name '*.ci' | sort) $(STACK_PROGRAM_CI)

# ---- the terminal programs' static RAM (issue 15.3) ----
# data + bss of cmz-decode and cmz-terminal within CM_DECODE_STATE_BUDGET + CM_PROGRAM_STATIC_BUDGET,
# cmz-view's within CM_VIEW_STATIC_BUDGET more (its frame)
.PHONY: check-ram
check-ram: $(B)/cmz-decode $(B)/cmz-terminal $(B)/cmz-view
	$(Q)CM_TEXT_BUDGET=$(if $(filter aarch64-%,$(TRIPLET)),$(call limit_of,$(PROFILE),CM_PROGRAM_TEXT_BUDGET)) \
		CM_VIEW_BUDGET=$(call limit_of,$(PROFILE),CM_VIEW_STATIC_BUDGET) \
		tests/tools/check_ram.sh $(CROSS_COMPILE)size $(CROSS_COMPILE)nm $(call limit_of,$(PROFILE),CM_DECODE_STATE_BUDGET) \
		$(call limit_of,$(PROFILE),CM_PROGRAM_STATIC_BUDGET) $(B)/cmz-decode $(B)/cmz-terminal $(B)/cmz-view
