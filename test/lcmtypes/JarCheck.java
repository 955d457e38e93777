// The alight types jar, loaded next to lcm.jar: LCM's class discoverer (what lcm-spy uses) must
// find one class for every .lcm file, and decode every event of a log written by C++.
// Usage: java -cp alight_lcmtypes.jar:lcm.jar:. JarCheck LOG LCMTYPES_DIR
import java.io.DataInputStream;
import java.io.ByteArrayInputStream;
import java.io.File;
import java.io.IOException;
import lcm.logging.Log;
import lcm.spy.LCMTypeDatabase;

public class JarCheck {
  public static void main(String[] args) throws Exception {
    LCMTypeDatabase db = new LCMTypeDatabase();
    int failures = 0;
    File[] lcmFiles = new File(args[1]).listFiles((dir, name) -> name.endsWith(".lcm"));
    for (File f : lcmFiles) {
      String type = f.getName().replace(".lcm", "");
      Class<?> cls = Class.forName("alight." + type);
      long fp = cls.getField("LCM_FINGERPRINT").getLong(null);
      Class<?> found = db.getClassByFingerprint(fp);
      if (found != cls) {
        System.err.println("not found by the type database: alight." + type);
        failures++;
      }
    }
    Log log = new Log(args[0], "r");
    int events = 0;
    while (true) {
      Log.Event ev;
      try {
        ev = log.readNext();
      } catch (IOException eof) {
        break;
      }
      long fp = new DataInputStream(new ByteArrayInputStream(ev.data)).readLong();
      Class<?> cls = db.getClassByFingerprint(fp);
      if (cls == null) {
        System.err.println("no class for event on " + ev.channel);
        failures++;
        continue;
      }
      cls.getConstructor(java.io.DataInput.class)
          .newInstance(new DataInputStream(new ByteArrayInputStream(ev.data)));
      events++;
    }
    if (events != 14) {
      System.err.println("decoded " + events + " events, expected 14");
      failures++;
    }
    System.out.println(lcmFiles.length + " types found, " + events + " events decoded");
    System.exit(failures == 0 ? 0 : 1);
  }
}
