# make install / make uninstall (docs/install.md): the programs, man pages, the systemd unit
# (contrib/curvestep.service.in with the paths filled in), bash completion, sample machine files
# (contrib/*.ini) and the documentation, under $(DESTDIR)$(PREFIX). uninstall removes exactly
# the files install writes (CS_INSTALLED) and the directories that are curvestep's own.
PREFIX         ?= /usr/local
BINDIR         ?= $(PREFIX)/bin
DATADIR        ?= $(PREFIX)/share
MANDIR         ?= $(DATADIR)/man
DOCDIR         ?= $(DATADIR)/doc/curvestep
SAMPLEDIR      ?= $(DATADIR)/curvestep
SYSTEMDUNITDIR ?= $(PREFIX)/lib/systemd/system
BASHCOMPDIR    ?= $(DATADIR)/bash-completion/completions
INSTALL        ?= install

CS_MAN1    := $(wildcard man/*.1)
CS_MAN5    := $(wildcard man/*.5)
CS_SAMPLES := $(wildcard contrib/*.ini)
CS_DOCS    := README.md $(wildcard docs/*.md)
CS_DOCIMG  := $(wildcard docs/img/*)
CS_INSTALLED := $(BINDIR)/curvestep $(BINDIR)/curvestep-sim \
  $(CS_MAN1:man/%=$(MANDIR)/man1/%) $(CS_MAN5:man/%=$(MANDIR)/man5/%) \
  $(SYSTEMDUNITDIR)/curvestep.service $(BASHCOMPDIR)/curvestep $(BASHCOMPDIR)/curvestep-sim \
  $(CS_SAMPLES:contrib/%=$(SAMPLEDIR)/%) $(addprefix $(DOCDIR)/,$(notdir $(CS_DOCS))) \
  $(CS_DOCIMG:docs/img/%=$(DOCDIR)/img/%)

# The unit depends on where the program is installed: regenerate it when PREFIX changes.
$(BUILD)/curvestep.service: contrib/curvestep.service.in cs-force
	@mkdir -p $(@D)
	@sed -e 's|@BINDIR@|$(BINDIR)|g' -e 's|@DOCDIR@|$(DOCDIR)|g' $< >$@.tmp
	@if cmp -s $@.tmp $@; then rm -f $@.tmp; else mv $@.tmp $@; fi

.PHONY: install uninstall cs-force
cs-force:
install: $(BUILD)/curvestep $(BUILD)/curvestep-sim $(BUILD)/curvestep.service
	$(INSTALL) -d $(DESTDIR)$(BINDIR) $(DESTDIR)$(MANDIR)/man1 $(DESTDIR)$(MANDIR)/man5 \
	  $(DESTDIR)$(SYSTEMDUNITDIR) $(DESTDIR)$(BASHCOMPDIR) $(DESTDIR)$(SAMPLEDIR) \
	  $(DESTDIR)$(DOCDIR)/img
	$(INSTALL) -m 755 $(BUILD)/curvestep $(BUILD)/curvestep-sim $(DESTDIR)$(BINDIR)/
	$(INSTALL) -m 644 $(CS_MAN1) $(DESTDIR)$(MANDIR)/man1/
	$(INSTALL) -m 644 $(CS_MAN5) $(DESTDIR)$(MANDIR)/man5/
	$(INSTALL) -m 644 $(BUILD)/curvestep.service $(DESTDIR)$(SYSTEMDUNITDIR)/
	$(INSTALL) -m 644 contrib/bash-completion/curvestep $(DESTDIR)$(BASHCOMPDIR)/
	ln -sf curvestep $(DESTDIR)$(BASHCOMPDIR)/curvestep-sim
	$(if $(CS_SAMPLES),$(INSTALL) -m 644 $(CS_SAMPLES) $(DESTDIR)$(SAMPLEDIR)/)
	$(INSTALL) -m 644 $(CS_DOCS) $(DESTDIR)$(DOCDIR)/
	$(if $(CS_DOCIMG),$(INSTALL) -m 644 $(CS_DOCIMG) $(DESTDIR)$(DOCDIR)/img/)

uninstall:
	rm -f $(addprefix $(DESTDIR),$(CS_INSTALLED))
	rmdir $(DESTDIR)$(DOCDIR)/img $(DESTDIR)$(DOCDIR) $(DESTDIR)$(SAMPLEDIR) 2>/dev/null || true

# make deb (docs/install.md): the Debian package, built by dpkg-buildpackage (debhelper, debian/)
# in a copy of the source tree under $(BUILD)/deb, so its by-products stay in build/; the
# package lands in $(BUILD)/ and lintian's verdict is printed (each remaining tag is explained in
# docs/install.md). Not part of make test (about a minute).
CS_DEB_VERSION = $(shell dpkg-parsechangelog -S Version 2>/dev/null)
.PHONY: deb
deb:
	rm -rf $(BUILD)/deb && mkdir -p $(BUILD)/deb/curvestep
	if git rev-parse --git-dir >/dev/null 2>&1; then git ls-files -co --exclude-standard -z; \
	  else find . -path ./$(BUILD) -prune -o -type f -print0; fi \
	  | tar --null -T - -cf - | tar -xf - -C $(BUILD)/deb/curvestep
	cd $(BUILD)/deb/curvestep && dpkg-buildpackage --build=binary --no-sign >../dpkg-buildpackage.log 2>&1 \
	  || { tail -30 ../dpkg-buildpackage.log; exit 1; }
	mv $(BUILD)/deb/curvestep_$(CS_DEB_VERSION)_*.deb $(BUILD)/
	lintian --info $(BUILD)/curvestep_$(CS_DEB_VERSION)_*.deb || true
	@ls -l $(BUILD)/curvestep_$(CS_DEB_VERSION)_*.deb

# make deb-check: install the package with apt, check it, purge it (scripts/deb-check.sh; changes
# the system, so never part of make test).
.PHONY: deb-check
deb-check: deb
	@bash scripts/deb-check.sh $(BUILD)/curvestep_$(CS_DEB_VERSION)_*.deb
