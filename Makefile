# Installs bearingd as a systemd service. See docs/SYSTEMD.md.
#
#   make install                      build (cargo build --release --locked) and install under /usr
#                                     the service bearingd and the lab bearingd-lab
#   make install-service              the service alone (edge boxes: no training, no plots)
#   make install BIN=path/to/bearingd install an already built binary (e.g. a cross-built one);
#                                     LAB_BIN=path/to/bearingd-lab likewise for the lab
#   make install DESTDIR=/srv/root    stage into another root (packaging, VM images)
#   make uninstall                    remove what install put there (not the config, logs, user)
#   make cli-docs                     regenerate docs/cli (man pages, completion scripts) with the
#                                     lab after a change of either command line; a test fails
#                                     until they match (crates/bearingd-lab/tests/cli_docs.rs)
#
# What goes where (PREFIX=/usr by default):
#   $(PREFIX)/bin/bearingd                         the service binary
#   $(PREFIX)/bin/bearingd-lab                     the lab binary (not with install-service)
#   $(PREFIX)/lib/systemd/system/bearingd.service  the unit (paths rewritten if PREFIX != /usr)
#   $(PREFIX)/lib/sysusers.d/bearingd.conf         the static system user and group `bearingd`
#   $(PREFIX)/lib/tmpfiles.d/bearingd.conf         /dev/cpu_dma_latency writable by that group
#   $(PREFIX)/share/doc/bearingd/SYSTEMD.md        the unit's Documentation=
#   $(PREFIX)/share/bearingd/models/*.safetensors  the learned models, one per catalog bearing
#                                                  (twin.learned_model; docs/PHYSICS.md)
#   $(PREFIX)/share/man/man1/bearingd*.1           man pages of each program and command
#                                                  (bearingd-lab*.1 not with install-service)
#   $(PREFIX)/share/bash-completion/completions/bearingd, zsh/vendor-completions/_bearingd,
#   $(PREFIX)/share/fish/vendor_completions.d/bearingd.fish   completions (and bearingd-lab's)
#   /etc/bearingd/bearingd.toml                    the default config, never overwritten
#
# On a live system (no DESTDIR) install also creates the user (systemd-sysusers) and reloads
# systemd; with DESTDIR those are left to whoever boots the root (or `systemd-sysusers
# --root=DIR`), as a package's postinst would do them.

PREFIX ?= /usr
DESTDIR ?=
BINDIR ?= $(PREFIX)/bin
UNITDIR ?= $(PREFIX)/lib/systemd/system
SYSUSERSDIR ?= $(PREFIX)/lib/sysusers.d
TMPFILESDIR ?= $(PREFIX)/lib/tmpfiles.d
DOCDIR ?= $(PREFIX)/share/doc/bearingd
MODELDIR ?= $(PREFIX)/share/bearingd/models
MANDIR ?= $(PREFIX)/share/man/man1
BASHCOMPDIR ?= $(PREFIX)/share/bash-completion/completions
ZSHCOMPDIR ?= $(PREFIX)/share/zsh/vendor-completions
FISHCOMPDIR ?= $(PREFIX)/share/fish/vendor_completions.d
# The config path is fixed: the unit and the docs name /etc/bearingd/bearingd.toml.
CONFDIR = /etc/bearingd
CARGO ?= cargo
INSTALL ?= install
# Already built binaries to install; empty: build target/release/bearingd (and bearingd-lab)
# with cargo.
BIN ?=
LAB_BIN ?=

ifeq ($(BIN),)
BINARY := target/release/bearingd
else
BINARY := $(BIN)
endif
ifeq ($(LAB_BIN),)
LAB_BINARY := target/release/bearingd-lab
else
LAB_BINARY := $(LAB_BIN)
endif

# Man pages and completion scripts are installed from the checkout (docs/cli, written by the
# lab: `make cli-docs`), so that install-service and BIN= (a cross-built binary that cannot run
# here) need no lab and run nothing they install.
LAB_MANS := $(wildcard docs/cli/man/bearingd-lab.1 docs/cli/man/bearingd-lab-*.1)
SERVICE_MANS := $(filter-out $(LAB_MANS),$(wildcard docs/cli/man/bearingd*.1))
# The learned models the service may judge with (twin.learned_model), from the checkout.
MODELS := $(wildcard models/*.safetensors)

.PHONY: all build build-lab install install-service uninstall cli-docs

all: build build-lab

build:
ifeq ($(BIN),)
	$(CARGO) build --release --locked -p bearingd
else
	@test -x "$(BIN)" || { echo "make: BIN=$(BIN) is not an executable file" >&2; exit 1; }
endif

build-lab:
ifeq ($(LAB_BIN),)
	$(CARGO) build --release --locked -p bearingd-lab
else
	@test -x "$(LAB_BIN)" || { echo "make: LAB_BIN=$(LAB_BIN) is not an executable file" >&2; exit 1; }
endif

# Both binaries: `bearingd evaluate ...` and the other lab commands run bearingd-lab.
install: install-service build-lab
	$(INSTALL) -D -m 0755 "$(LAB_BINARY)" "$(DESTDIR)$(BINDIR)/bearingd-lab"
	$(INSTALL) -m 0644 $(LAB_MANS) "$(DESTDIR)$(MANDIR)/"
	$(INSTALL) -D -m 0644 docs/cli/completions/bearingd-lab "$(DESTDIR)$(BASHCOMPDIR)/bearingd-lab"
	$(INSTALL) -D -m 0644 docs/cli/completions/_bearingd-lab "$(DESTDIR)$(ZSHCOMPDIR)/_bearingd-lab"
	$(INSTALL) -D -m 0644 docs/cli/completions/bearingd-lab.fish "$(DESTDIR)$(FISHCOMPDIR)/bearingd-lab.fish"

install-service: build
	$(INSTALL) -D -m 0755 "$(BINARY)" "$(DESTDIR)$(BINDIR)/bearingd"
	$(INSTALL) -d -m 0755 "$(DESTDIR)$(UNITDIR)"
	sed -e 's|/usr/bin/bearingd|$(BINDIR)/bearingd|g' \
	    -e 's|/usr/share/doc/bearingd/|$(DOCDIR)/|g' \
	    systemd/bearingd.service > "$(DESTDIR)$(UNITDIR)/bearingd.service"
	chmod 0644 "$(DESTDIR)$(UNITDIR)/bearingd.service"
	$(INSTALL) -D -m 0644 systemd/bearingd.sysusers "$(DESTDIR)$(SYSUSERSDIR)/bearingd.conf"
	$(INSTALL) -D -m 0644 systemd/bearingd.tmpfiles "$(DESTDIR)$(TMPFILESDIR)/bearingd.conf"
	$(INSTALL) -D -m 0644 docs/SYSTEMD.md "$(DESTDIR)$(DOCDIR)/SYSTEMD.md"
	$(INSTALL) -d -m 0755 "$(DESTDIR)$(MODELDIR)"
	$(INSTALL) -m 0644 $(MODELS) "$(DESTDIR)$(MODELDIR)/"
	$(INSTALL) -d -m 0755 "$(DESTDIR)$(MANDIR)"
	$(INSTALL) -m 0644 $(SERVICE_MANS) "$(DESTDIR)$(MANDIR)/"
	$(INSTALL) -D -m 0644 docs/cli/completions/bearingd "$(DESTDIR)$(BASHCOMPDIR)/bearingd"
	$(INSTALL) -D -m 0644 docs/cli/completions/_bearingd "$(DESTDIR)$(ZSHCOMPDIR)/_bearingd"
	$(INSTALL) -D -m 0644 docs/cli/completions/bearingd.fish "$(DESTDIR)$(FISHCOMPDIR)/bearingd.fish"
	$(INSTALL) -d -m 0755 "$(DESTDIR)$(CONFDIR)"
	@if [ -e "$(DESTDIR)$(CONFDIR)/bearingd.toml" ]; then \
	  echo "kept the existing $(DESTDIR)$(CONFDIR)/bearingd.toml (the default is in $(DOCDIR) as bearingd.toml.default)"; \
	  $(INSTALL) -m 0644 config/bearingd.toml "$(DESTDIR)$(DOCDIR)/bearingd.toml.default"; \
	else \
	  $(INSTALL) -m 0644 config/bearingd.toml "$(DESTDIR)$(CONFDIR)/bearingd.toml"; \
	fi
	@if [ -z "$(DESTDIR)" ]; then \
	  if command -v systemd-sysusers >/dev/null; then systemd-sysusers bearingd.conf; \
	  else echo "no systemd-sysusers: create the user with: useradd --system --no-create-home --home-dir /nonexistent --shell /usr/sbin/nologin bearingd"; fi; \
	  if command -v systemd-tmpfiles >/dev/null; then systemd-tmpfiles --create bearingd.conf; fi; \
	  if [ -d /run/systemd/system ]; then systemctl daemon-reload; fi; \
	  echo "installed; edit $(CONFDIR)/bearingd.toml, then: systemctl enable --now bearingd"; \
	fi

uninstall:
	@if [ -z "$(DESTDIR)" ] && [ -d /run/systemd/system ] && systemctl is-enabled --quiet bearingd 2>/dev/null; then \
	  echo "bearingd is enabled: systemctl disable --now bearingd first" >&2; exit 1; \
	fi
	rm -f "$(DESTDIR)$(BINDIR)/bearingd" "$(DESTDIR)$(BINDIR)/bearingd-lab" "$(DESTDIR)$(UNITDIR)/bearingd.service" \
	      "$(DESTDIR)$(SYSUSERSDIR)/bearingd.conf" "$(DESTDIR)$(TMPFILESDIR)/bearingd.conf" \
	      "$(DESTDIR)$(DOCDIR)/SYSTEMD.md" \
	      "$(DESTDIR)$(DOCDIR)/bearingd.toml.default"
	rm -f "$(DESTDIR)$(MANDIR)"/bearingd.1 "$(DESTDIR)$(MANDIR)"/bearingd-*.1
	rm -f $(addprefix "$(DESTDIR)$(MODELDIR)"/,$(notdir $(MODELS)))
	rmdir "$(DESTDIR)$(MODELDIR)" "$(DESTDIR)$(dir $(MODELDIR))" 2>/dev/null || true
	rm -f "$(DESTDIR)$(BASHCOMPDIR)/bearingd" "$(DESTDIR)$(BASHCOMPDIR)/bearingd-lab" \
	      "$(DESTDIR)$(ZSHCOMPDIR)/_bearingd" "$(DESTDIR)$(ZSHCOMPDIR)/_bearingd-lab" \
	      "$(DESTDIR)$(FISHCOMPDIR)/bearingd.fish" "$(DESTDIR)$(FISHCOMPDIR)/bearingd-lab.fish"
	rmdir "$(DESTDIR)$(DOCDIR)" 2>/dev/null || true
	@if [ -z "$(DESTDIR)" ] && [ -d /run/systemd/system ]; then systemctl daemon-reload; fi
	@echo "left in place: $(CONFDIR) (your config), /var/lib/bearingd, /var/log/bearingd (data) and the bearingd user"

# docs/cli from the current command lines (the service embeds docs/cli/completions: rebuild it
# after this). Stale pages of removed commands go first.
cli-docs: build-lab
	rm -f docs/cli/man/*.1
	"$(LAB_BINARY)" man --out docs/cli/man
	"$(LAB_BINARY)" completions --out docs/cli/completions
