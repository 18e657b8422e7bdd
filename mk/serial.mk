# mk/serial.mk - the serial, fd and in-memory/fault transports (platform/), their tests on real ptys,
# and the fault-injecting pty relay (tests/tools/pty_relay).  Needs nothing beyond libc.
#
#   make check-serial            build and run the platform tests (TAP lines, then "N passed, N failed")
#   make check-serial-aarch64    the same tests built for aarch64, run under qemu-aarch64 (the relay
#                                they start is this machine's build: a qemu-user process cannot exec
#                                a foreign binary)
# The objects come from the generic $(call bdir,X)/%.o rule; the back ends are built for any profile
# (the terminal links $(call bdir,terminal)/platform/cm_transport_serial.o and cm_transport_fd.o).

SERIAL_B := $(call bdir,host)
SERIAL_OBJS := $(addprefix $(SERIAL_B)/platform/,cm_transport_fd.o cm_transport_serial.o \
	fake/cm_transport_fault.o fake/cm_transport_mem.o)
SERIAL_TEST_NAMES := $(patsubst tests/platform/%.c,%,$(sort $(wildcard tests/platform/test_*.c)))
SERIAL_TESTS := $(addprefix $(SERIAL_B)/tests/platform/,$(SERIAL_TEST_NAMES))
PTY_RELAY := $(SERIAL_B)/tests/tools/pty_relay

$(SERIAL_TESTS): $(SERIAL_B)/tests/platform/%: $(SERIAL_B)/tests/platform/%.o $(SERIAL_OBJS)
	$(call say,LD      ,$@)
	$(Q)$(CC) $(CFLAGS) $(LDFLAGS) -o $@ $^

$(PTY_RELAY): $(SERIAL_B)/tests/tools/pty_relay.o $(SERIAL_B)/platform/fake/cm_transport_fault.o
	$(call say,LD      ,$@)
	$(Q)$(CC) $(CFLAGS) $(LDFLAGS) -o $@ $^

.PHONY: serial-tests check-serial check-serial-aarch64
serial-tests: $(SERIAL_TESTS) $(PTY_RELAY)

# $(1) = directory of the test binaries, $(2) = runner prefix (qemu-aarch64 or empty), $(3) = relay
define SERIAL_RUN
	$(Q)pass=0; fail=0; skip=0; for t in $(addprefix $(1)/,$(SERIAL_TEST_NAMES)); do \
		echo "# $$t"; \
		out=$$(CM_PTY_RELAY=$(3) timeout 300 $(2) $$t 2>&1); rc=$$?; echo "$$out"; \
		np=$$(grep -c '^ok ' <<<"$$out"); ns=$$(grep -c '^not ok [0-9]* # SKIP' <<<"$$out"); \
		nf=$$(( $$(grep -c '^not ok ' <<<"$$out") - ns )); skip=$$((skip + ns)); \
		if [ $$rc -ne 0 ] && [ $$nf -eq 0 ]; then nf=1; echo "not ok - $$t exited with status $$rc"; fi; \
		pass=$$((pass + np)); fail=$$((fail + nf)); \
	done; [ $$skip -eq 0 ] || echo "$$skip skipped (see SKIP lines above)"; \
	echo "$$pass passed, $$fail failed"; [ $$fail -eq 0 ]
endef

check-serial: serial-tests
	$(call SERIAL_RUN,$(SERIAL_B)/tests/platform,,$(abspath $(PTY_RELAY)))

SERIAL_A64 := $(BUILD_ROOT)/aarch64-linux-gnu-host
check-serial-aarch64: $(PTY_RELAY)
	$(Q)$(MAKE) --no-print-directory -s CROSS_COMPILE=aarch64-linux-gnu- CC=aarch64-linux-gnu-gcc \
		AR=aarch64-linux-gnu-ar PKG_CONFIG=aarch64-linux-gnu-pkg-config \
		$(addprefix $(SERIAL_A64)/tests/platform/,$(SERIAL_TEST_NAMES))
	$(call SERIAL_RUN,$(SERIAL_A64)/tests/platform,$(SERIAL_QEMU),$(abspath $(PTY_RELAY)))

# without a multiarch libc6:arm64, qemu needs the cross sysroot (with it, -L must not be given:
# hw-testing NOTES pitfall 9)
SERIAL_QEMU = qemu-aarch64$(if $(wildcard /usr/lib/aarch64-linux-gnu/libc.so.6),, -L /usr/aarch64-linux-gnu)
