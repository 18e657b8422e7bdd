# mk/usb.mk - the USB back ends of cm_transport (platform/cm_transport_usb.c: libusb host side, the
# terminal; platform/cm_transport_ffs.c: FunctionFS gadget side, the workstation) and their test.
#
#   make usb-tools          $(call bdir,host)/tests/platform/usb_echo and the back ends' objects
#   make check-usb-build    the same with gcc, clang and aarch64-linux-gnu-gcc (compile and link), and
#                           `usb_echo --selftest` (no hardware) natively and under qemu-aarch64
#   make check-usb-vm       the echo and unplug test in a VM (dummy_hcd + FunctionFS); needs
#                           USB_VM_RUN=.../run-in-vm.sh (a VM made by make-vm.sh)
#
# libusb-1.0 >= 1.0.26 (Debian 12) is found with $(PKG_CONFIG), so a cross build looks in the target's
# pkg-config (PKG_CONFIG=aarch64-linux-gnu-pkg-config).  Without it these targets print what to
# install and do nothing; `make` itself never depends on libusb.

USB_LIBUSB_MIN := 1.0.26
USB_LIBUSB_STATE := $(shell if $(PKG_CONFIG) --exists libusb-1.0 2>/dev/null; then \
	$(PKG_CONFIG) --atleast-version=$(USB_LIBUSB_MIN) libusb-1.0 && echo ok || echo old; else echo none; fi)
ifeq ($(USB_LIBUSB_STATE),ok)
USB_LIBUSB_CFLAGS := $(shell $(PKG_CONFIG) --cflags libusb-1.0)
USB_LIBUSB_LIBS := $(shell $(PKG_CONFIG) --libs libusb-1.0)
else ifeq ($(USB_LIBUSB_STATE),old)
USB_LIBUSB_WHY := libusb-1.0 $(shell $(PKG_CONFIG) --modversion libusb-1.0) is older than $(USB_LIBUSB_MIN) \
	($(PKG_CONFIG)): the USB back end is not built
else
USB_DEB_ARCH := $(if $(filter aarch64-%,$(TRIPLET)),:arm64,$(if $(filter arm-%,$(TRIPLET)),:armhf))
USB_LIBUSB_WHY := libusb-1.0 not found by $(PKG_CONFIG) (install libusb-1.0-0-dev$(USB_DEB_ARCH)): \
	the USB back end is not built
endif

USB_ECHO := $(call bdir,host)/tests/platform/usb_echo

# the libusb back end needs libusb's include directory, in every profile (the terminal links it)
define USB_PROFILE_RULES
$(call bdir,$(1))/platform/cm_transport_usb.o: platform/cm_transport_usb.c
	@mkdir -p $$(@D)
	$$(call say,CC      ,$$@)
	$$(Q)$$(CC) $$(CM_INC_ALL) $$(USB_LIBUSB_CFLAGS) $$(CPPFLAGS) $$(CM_STD) $$(CM_WARN) $$(CFLAGS) \
		$$(DEPFLAGS) -c $$< -o $$@
endef
$(foreach p,$(PROFILES),$(eval $(call USB_PROFILE_RULES,$(p))))

.PHONY: usb-tools check-usb-build check-usb-vm
ifeq ($(USB_LIBUSB_STATE),ok)
$(USB_ECHO): $(call bdir,host)/tests/platform/usb_echo.o $(call bdir,host)/platform/cm_transport_usb.o \
		$(call bdir,host)/platform/cm_transport_ffs.o
	$(call say,LD      ,$@)
	$(Q)$(CC) $(CFLAGS) $(LDFLAGS) -o $@ $^ $(USB_LIBUSB_LIBS)

usb-tools: $(USB_ECHO) $(call bdir,terminal)/platform/cm_transport_usb.o
else
$(USB_ECHO):
	@echo "$@: $(USB_LIBUSB_WHY)" >&2; exit 1

usb-tools:
	@echo "# SKIP usb-tools ($(TRIPLET)): $(USB_LIBUSB_WHY)"
endif

# gcc (this Makefile's CC), clang and the aarch64 cross compiler each build and link usb_echo; a
# missing compiler or target libusb is a SKIP line, not a failure
USB_CROSS := aarch64-linux-gnu- arm-linux-gnueabihf-
check-usb-build:
	$(Q)n=0; fail=0; \
	try() { n=$$((n+1)); label=$$1; shift; \
		if out=$$("$$@" 2>&1); then \
			if grep -q '^# SKIP' <<<"$$out"; then grep '^# SKIP' <<<"$$out"; n=$$((n-1)); \
			else echo "ok $$n - usb back ends build and link: $$label"; fi; \
		else echo "not ok $$n - usb back ends: $$label"; echo "$$out" | tail -n 20; fail=$$((fail+1)); fi; }; \
	try "$(CC)" $(MAKE) --no-print-directory -s usb-tools; \
	if command -v clang >/dev/null; then \
		try clang $(MAKE) --no-print-directory -s CC=clang BUILD_ROOT=$(BUILD_ROOT)/clang-usb CM_NO_STACK_FLAGS=1 usb-tools; \
	else echo "# SKIP clang: not installed"; fi; \
	for x in $(USB_CROSS); do \
		if command -v $${x}gcc >/dev/null; then \
			try "$${x}gcc" $(MAKE) --no-print-directory -s CROSS_COMPILE=$$x CC=$${x}gcc AR=$${x}ar \
				PKG_CONFIG=$${x}pkg-config usb-tools; \
		else echo "# SKIP $${x}gcc: not installed"; fi; \
	done; \
	selftest() { label=$$1; shift; \
		if out=$$("$$@" --selftest 2>&1); then n=$$((n+1)); echo "ok $$n - usb_echo --selftest ($$label): $$(grep -c '^ok' <<<"$$out") checks"; \
		else n=$$((n+1)); fail=$$((fail+1)); echo "not ok $$n - usb_echo --selftest ($$label)"; grep '^not ok' <<<"$$out"; fi; }; \
	[ ! -x $(USB_ECHO) ] || selftest $(TRIPLET) $(USB_ECHO); \
	a64=$(BUILD_ROOT)/aarch64-linux-gnu-host/tests/platform/usb_echo; \
	if [ -x $$a64 ] && command -v qemu-aarch64 >/dev/null; then selftest "aarch64, qemu-aarch64" qemu-aarch64 $$a64; fi; \
	[ $$fail -eq 0 ]

# the VM test (tests/hw/vm-usb-transport.sh) runs as root inside a VM with the Debian kernel's
# dummy_hcd; USB_VM_RUN is the harness's run-in-vm.sh
USB_VM_RUN ?= $(firstword $(wildcard tests/hw/run-in-vm.sh))
check-usb-vm: usb-tools
	$(Q)if [ -z "$(USB_VM_RUN)" ]; then \
		echo "# SKIP check-usb-vm: set USB_VM_RUN=/path/to/run-in-vm.sh (a VM built by its make-vm.sh)"; \
	else $(USB_VM_RUN) -t 300 -- bash tests/hw/vm-usb-transport.sh $(USB_ECHO); fi

# the VM harness (mk/hw.mk) runs tests/hw/vm-usb-transport.sh with this echo program
ifeq ($(USB_LIBUSB_STATE),ok)
HW_TEST_DEPS += $(USB_ECHO)
endif
