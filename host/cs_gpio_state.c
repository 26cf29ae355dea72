/* cs_gpio_state: the GPIO machine's state file (see cs_gpio_state.h). */
#include "cs_gpio_state.h"

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

int cs_gpio_state_path(const char *cfg_state, const char *record, const char *chip, char *out,
                       size_t outlen)
{
    if (cfg_state != NULL && cfg_state[0] != '\0') {
        snprintf(out, outlen, "%s", cfg_state);
        return 0;
    }
    if (record != NULL) {
        snprintf(out, outlen, "%s.state", record);
        return 0;
    }
    /* never a fixed name in a world-writable directory such as /tmp: another user could plant
     * it (or a link in its place) and decide the alarm */
    const char *run = getenv("XDG_RUNTIME_DIR"), *home = getenv("HOME");
    char name[64];
    snprintf(name, sizeof name, "%s", chip);
    for (char *p = name; *p; p++)
        if (*p == '/')
            *p = '_';
    if (run != NULL && run[0] == '/')
        snprintf(out, outlen, "%s/curvestep-gpio-%s.state", run, name);
    else if (home != NULL && home[0] == '/')
        snprintf(out, outlen, "%s/.curvestep-gpio-%s.state", home, name);
    else
        return -1;
    return 0;
}

int cs_gpio_state_load(const char *path, cs_gpio_state_t *s, char *err, size_t errlen)
{
    memset(s, 0, sizeof *s);
    FILE *f = fopen(path, "r");
    if (f == NULL) {
        if (errno == ENOENT)
            return 0;
        snprintf(err, errlen, "%s: %s", path, strerror(errno));
        return -1;
    }
    char line[256];
    int bad = 0;
    while (fgets(line, sizeof line, f)) {
        unsigned a, in, h;
        long p[CS_AXES];
        long long o[CS_AXES];
        if (line[0] == '#' || line[0] == '\n')
            continue;
        if (sscanf(line, "alarm %u inputs %x", &a, &in) == 2 && a < 256) {
            s->alarm = (uint8_t)a;
            s->inputs = (uint16_t)in;
        } else if (sscanf(line, "pos %ld %ld %ld %ld", &p[0], &p[1], &p[2], &p[3]) == 4) {
            for (unsigned i = 0; i < CS_AXES; i++)
                s->pos[i] = (int32_t)p[i];
        } else if (sscanf(line, "off %lld %lld %lld %lld", &o[0], &o[1], &o[2], &o[3]) == 4) {
            for (unsigned i = 0; i < CS_AXES; i++)
                s->off[i] = o[i];
        } else if (sscanf(line, "homed %x", &h) == 1) {
            s->homed = (uint16_t)h;
        } else {
            bad = 1;
        }
    }
    fclose(f);
    if (bad) {
        snprintf(err, errlen, "%s: not a curvestep GPIO state file (remove it to start afresh)",
                 path);
        return -1;
    }
    return 0;
}

int cs_gpio_state_save(const char *path, const cs_gpio_state_t *s)
{
    char tmp[400];
    snprintf(tmp, sizeof tmp, "%s.tmp", path);
    int fd = open(tmp, O_WRONLY | O_CREAT | O_TRUNC | O_NOFOLLOW, 0644);
    FILE *f = fd >= 0 ? fdopen(fd, "w") : NULL;
    if (f == NULL) {
        if (fd >= 0)
            close(fd);
        return -1;
    }
    fprintf(f, "# curvestep gpio state: the alarm, the machine position (steps), the recorder's\n"
               "# physical offset (steps), the axes homed\n");
    fprintf(f, "alarm %u inputs 0x%03x\n", (unsigned)s->alarm, (unsigned)s->inputs);
    fprintf(f, "pos %ld %ld %ld %ld\n", (long)s->pos[0], (long)s->pos[1], (long)s->pos[2],
            (long)s->pos[3]);
    fprintf(f, "off %lld %lld %lld %lld\n", (long long)s->off[0], (long long)s->off[1],
            (long long)s->off[2], (long long)s->off[3]);
    fprintf(f, "homed 0x%x\n", (unsigned)s->homed);
    if (fclose(f) != 0)
        return -1;
    return rename(tmp, path);
}
