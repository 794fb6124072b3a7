// Decodes every event of an lcm-logger recording with the message types of a jar
// (build/lcmtypes/lcmtypes_hbirl.jar) through LCM's Java library, finding each event's
// class by its fingerprint as lcm-spy does (lcm.spy.LCMTypeDatabase scans the class path).
// Prints the count per type; exits 1 if an event of a known type does not decode.
//   java -cp /usr/share/java/lcm.jar:lcmtypes_hbirl.jar:. DecodeRecording RUN.lcmlog
import java.io.ByteArrayInputStream;
import java.io.DataInputStream;
import java.io.EOFException;
import java.util.Map;
import java.util.TreeMap;

public class DecodeRecording {
  public static void main(String[] args) throws Exception {
    lcm.spy.LCMTypeDatabase types = new lcm.spy.LCMTypeDatabase();
    lcm.logging.Log log = new lcm.logging.Log(args[0], "r");
    Map<String, Integer> decoded = new TreeMap<>();
    int unknown = 0;
    for (;;) {
      lcm.logging.Log.Event event;
      try {
        event = log.readNext();
      } catch (EOFException end) {
        break;
      }
      if (event.data.length < 8) {
        ++unknown;
        continue;
      }
      long fingerprint = new DataInputStream(new ByteArrayInputStream(event.data)).readLong();
      Class<?> type = types.getClassByFingerprint(fingerprint);
      if (type == null) {
        ++unknown;  // LCM's self-test and the like
        continue;
      }
      try {  // the generated constructor decodes (trailing bytes -- a run key's tag -- are not read)
        type.getConstructor(byte[].class).newInstance((Object) event.data);
      } catch (Exception e) {
        System.out.println("event on " + event.channel + " does not decode as " + type.getName() + ": " + e.getCause());
        System.exit(1);
      }
      decoded.merge(type.getName(), 1, Integer::sum);
    }
    for (Map.Entry<String, Integer> e : decoded.entrySet()) System.out.println(e.getKey() + " " + e.getValue());
    System.out.println("unknown " + unknown);
  }
}
